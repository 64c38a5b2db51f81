-- The knowledge base (docs/DIAGNOSIS.md, docs/FLEET.md): unit types with
-- nominal parameters, units with their modules and installation history,
-- analyses as jobs with their queryable results, failure modes with
-- signatures, failure records (the seed paper's "refusals database") and
-- diagnoses with their ranked candidates.

-- Unit types and the nominal values (with tolerances) of their error-model
-- parameters. Seeded at server start from data/unit-types/*.json.
CREATE TABLE unit_types (
  unit_type    text PRIMARY KEY,          -- "INS-2000", the {unit_type} of unitTypes/{unit_type}
  display_name text NOT NULL,
  description  text NOT NULL DEFAULT '',
  update_time  timestamptz NOT NULL DEFAULT now()
);

CREATE TABLE nominal_parameters (
  unit_type text NOT NULL REFERENCES unit_types (unit_type) ON DELETE CASCADE,
  parameter text NOT NULL,
  value     double precision NOT NULL,
  tolerance double precision NOT NULL CHECK (tolerance > 0),
  unit      text NOT NULL DEFAULT '',
  position  integer NOT NULL,  -- order of the data file
  PRIMARY KEY (unit_type, parameter)
);

-- The replaceable parts of a unit.
CREATE TABLE module_roles (
  role        text PRIMARY KEY,
  description text NOT NULL
);
INSERT INTO module_roles (role, description) VALUES
  ('gyro.x', 'dynamically tuned gyro, sensitive axis x'),
  ('gyro.y', 'dynamically tuned gyro, sensitive axis y'),
  ('gyro.z', 'dynamically tuned gyro, sensitive axis z'),
  ('acc.x', 'pendulous accelerometer, sensitive axis x'),
  ('acc.y', 'pendulous accelerometer, sensitive axis y'),
  ('acc.z', 'pendulous accelerometer, sensitive axis z'),
  ('interface_card', 'interface electronic card: sensor read-out, A/D conversion, reference voltage'),
  ('control_card', 'control card: rebalance loops, thermal control'),
  ('coupler', 'coupler: the mechanical mount of the sensor block'),
  ('power_supply', 'power supply');

-- Units: registered by their first run (0001); the fleet fields are filled
-- by the knowledge base or the fleet generator.
ALTER TABLE units
  ADD COLUMN batch           text,
  ADD COLUMN commission_time timestamptz,
  ADD COLUMN operating_hours double precision NOT NULL DEFAULT 0 CHECK (operating_hours >= 0),
  ADD COLUMN retired_time    timestamptz;
CREATE INDEX units_type_batch_idx ON units (unit_type, batch);

-- Installation history: one row per part installed in a role. The current
-- part has no removal.
CREATE TABLE modules (
  module_id       bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  unit_id         bigint NOT NULL REFERENCES units (unit_id) ON DELETE CASCADE,
  role            text NOT NULL REFERENCES module_roles (role),
  part_serial     text NOT NULL DEFAULT '',
  installed_time  timestamptz NOT NULL DEFAULT now(),
  installed_hours double precision NOT NULL DEFAULT 0,
  removed_time    timestamptz,
  removed_hours   double precision,
  removal_reason  text,
  CHECK ((removed_time IS NULL) = (removed_hours IS NULL))
);
CREATE UNIQUE INDEX modules_current_idx ON modules (unit_id, role) WHERE removed_time IS NULL;
CREATE INDEX modules_unit_idx ON modules (unit_id, role, installed_hours);
CREATE INDEX modules_role_idx ON modules (role);

-- When the bench test happened (generated history is older than its rows).
ALTER TABLE runs ADD COLUMN test_time timestamptz;

-- Analyses are jobs: claimed with FOR UPDATE SKIP LOCKED by any insdiagd's
-- worker, held under a lease the worker renews, taken up again when the
-- lease expires (at most max_attempts times).
CREATE TABLE analyses (
  analysis_id       uuid PRIMARY KEY DEFAULT gen_random_uuid(),
  run_id            uuid NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  unit_id           bigint NOT NULL REFERENCES units (unit_id) ON DELETE CASCADE,
  state             text NOT NULL DEFAULT 'QUEUED'
                    CHECK (state IN ('QUEUED', 'RUNNING', 'SUCCEEDED', 'FAILED', 'CANCELLED')),
  -- The requested model (insdiag.v1.ErrorModel, binary protobuf).
  request           bytea NOT NULL DEFAULT '',
  request_id        text UNIQUE,
  request_fingerprint text,
  lease_owner       text,
  lease_expires     timestamptz,
  attempts          integer NOT NULL DEFAULT 0,
  max_attempts      integer NOT NULL DEFAULT 3,
  cancel_requested  boolean NOT NULL DEFAULT false,
  progress_fraction double precision NOT NULL DEFAULT 0,
  progress_stage    text NOT NULL DEFAULT '',
  error_code        integer,
  error_message     text,
  -- Results (SUCCEEDED): the report (insdiag.v1.AnalysisReport, binary
  -- protobuf) and its headline figures as columns.
  report            bytea,
  verdict           text CHECK (verdict IN ('GOOD', 'OPERABLE', 'FAULTY')),
  nis_mean          double precision,
  log_likelihood    double precision,
  aic               double precision,
  bic               double precision,
  unit_hours        double precision,  -- the unit's operating hours at the test
  create_time       timestamptz NOT NULL DEFAULT now(),
  update_time       timestamptz NOT NULL DEFAULT now(),
  start_time        timestamptz,
  end_time          timestamptz
);
ALTER TABLE analyses ALTER COLUMN report SET STORAGE EXTERNAL;
-- The queue: only waiting and running jobs are indexed for the workers.
CREATE INDEX analyses_queued_idx ON analyses (create_time) WHERE state = 'QUEUED';
CREATE INDEX analyses_running_idx ON analyses (lease_expires) WHERE state = 'RUNNING';
CREATE INDEX analyses_list_idx ON analyses (create_time DESC, analysis_id DESC);
CREATE INDEX analyses_run_idx ON analyses (run_id);
CREATE INDEX analyses_unit_idx ON analyses (unit_id, create_time);

-- Parameter names as small keys: the fleet holds ~10 identified values per
-- analysis and millions of analyses.
CREATE TABLE parameter_names (
  parameter_id smallint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  name         text NOT NULL UNIQUE
);

CREATE TABLE identified_parameters (
  analysis_id  uuid NOT NULL REFERENCES analyses (analysis_id) ON DELETE CASCADE,
  parameter_id smallint NOT NULL REFERENCES parameter_names (parameter_id),
  value        double precision NOT NULL,
  std_error    double precision,
  method       text NOT NULL DEFAULT '',
  a_priori     double precision,
  PRIMARY KEY (analysis_id, parameter_id)
);
CREATE INDEX identified_parameters_parameter_idx ON identified_parameters (parameter_id);

CREATE TABLE effect_candidates (
  analysis_id        uuid NOT NULL REFERENCES analyses (analysis_id) ON DELETE CASCADE,
  name               text NOT NULL,
  family             text NOT NULL,
  per_family         boolean NOT NULL,  -- a family_candidates entry
  source             text NOT NULL DEFAULT '',
  statistic          double precision NOT NULL,
  degrees_of_freedom integer NOT NULL,
  p_value            double precision NOT NULL,
  p_value_holm       double precision NOT NULL,
  estimate           double precision NOT NULL,
  std_error          double precision,
  unit               text NOT NULL DEFAULT '',
  identifiable       boolean NOT NULL,
  predicted_delta_aic double precision,
  PRIMARY KEY (analysis_id, per_family, name)
);
CREATE INDEX effect_candidates_significant_idx ON effect_candidates (name) WHERE p_value_holm < 0.01;

CREATE TABLE channel_metrics (
  analysis_id       uuid NOT NULL REFERENCES analyses (analysis_id) ON DELETE CASCADE,
  channel           text NOT NULL,
  rms               double precision NOT NULL,
  fit_percent       double precision NOT NULL,
  nis_mean          double precision NOT NULL,
  whiteness_p_value double precision NOT NULL,
  sample_count      bigint NOT NULL,
  PRIMARY KEY (analysis_id, channel)
);

CREATE TABLE fault_intervals (
  analysis_id    uuid NOT NULL REFERENCES analyses (analysis_id) ON DELETE CASCADE,
  position       integer NOT NULL,
  channel        text NOT NULL,
  start_s        double precision NOT NULL,
  end_s          double precision NOT NULL,
  kind           text NOT NULL,
  peak_statistic double precision NOT NULL,
  PRIMARY KEY (analysis_id, position)
);

-- The residual series: epochs × channels, packed float64 little-endian (see
-- kb/src/analysis_store.cc, PackSeries).
CREATE TABLE analysis_series (
  analysis_id uuid PRIMARY KEY REFERENCES analyses (analysis_id) ON DELETE CASCADE,
  epochs      integer NOT NULL,
  data        bytea NOT NULL
);
ALTER TABLE analysis_series ALTER COLUMN data SET STORAGE EXTERNAL;

-- Failure modes with their signatures (data/failure-modes/*.json, seeded at
-- start-up); `change`/`spread` are refined by confirmed cases, the expert's
-- values are kept.
CREATE TABLE failure_modes (
  failure_mode        text PRIMARY KEY,   -- "dtg-bearing-wear.x"
  unit_type           text NOT NULL REFERENCES unit_types (unit_type) ON DELETE CASCADE,
  module_role         text NOT NULL REFERENCES module_roles (role),
  display_name        text NOT NULL,
  description         text NOT NULL,
  expert_rate_per_hour double precision NOT NULL CHECK (expert_rate_per_hour > 0),
  weibull_shape       double precision NOT NULL CHECK (weibull_shape > 0),
  weibull_scale_hours double precision NOT NULL CHECK (weibull_scale_hours > 0),
  update_time         timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX failure_modes_role_idx ON failure_modes (unit_type, module_role);

CREATE TABLE signature_terms (
  failure_mode    text NOT NULL REFERENCES failure_modes (failure_mode) ON DELETE CASCADE,
  position        integer NOT NULL,
  parameter       text NOT NULL,
  direction       text NOT NULL CHECK (direction IN ('UP', 'DOWN', 'EITHER')),
  scale           text NOT NULL CHECK (scale IN ('log_ratio', 'tolerance', 'z')),
  common          boolean NOT NULL DEFAULT false,
  fraction        double precision NOT NULL DEFAULT 1 CHECK (fraction > 0 AND fraction <= 1),
  expert_change   double precision NOT NULL CHECK (expert_change >= 0),
  expert_spread   double precision NOT NULL CHECK (expert_spread > 0),
  change          double precision NOT NULL,
  spread          double precision NOT NULL CHECK (spread > 0),
  confirmed_cases integer NOT NULL DEFAULT 0,
  PRIMARY KEY (failure_mode, position)
);

-- Diagnoses: the ranked hypotheses of one analysis.
CREATE TABLE diagnoses (
  diagnosis_id      uuid PRIMARY KEY DEFAULT gen_random_uuid(),
  analysis_id       uuid NOT NULL REFERENCES analyses (analysis_id) ON DELETE CASCADE,
  unit_id           bigint NOT NULL REFERENCES units (unit_id) ON DELETE CASCADE,
  fault_probability double precision NOT NULL,  -- 1 − P(healthy)
  top_module        text NOT NULL,
  top_failure_mode  text NOT NULL,
  top_probability   double precision NOT NULL,
  -- The Diagnosis message as created (binary protobuf), for GetDiagnosis.
  body              bytea NOT NULL,
  notes             text[] NOT NULL DEFAULT '{}',
  create_time       timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX diagnoses_unit_time_idx ON diagnoses (unit_id, create_time DESC);
CREATE INDEX diagnoses_analysis_idx ON diagnoses (analysis_id);
CREATE INDEX diagnoses_list_idx ON diagnoses (create_time DESC, diagnosis_id DESC);

CREATE TABLE diagnosis_candidates (
  diagnosis_id   uuid NOT NULL REFERENCES diagnoses (diagnosis_id) ON DELETE CASCADE,
  rank           integer NOT NULL,
  module         text NOT NULL,
  failure_mode   text NOT NULL,
  probability    double precision NOT NULL,
  evidence       text[] NOT NULL DEFAULT '{}',
  PRIMARY KEY (diagnosis_id, rank)
);

-- The refusals database (FRACAS records). A confirmed record names its
-- mode; no-fault-found records name the suspected module; censored records
-- mark a unit withdrawn without failing.
CREATE TABLE failure_records (
  record_id       uuid PRIMARY KEY DEFAULT gen_random_uuid(),
  module_id       bigint NOT NULL REFERENCES modules (module_id) ON DELETE CASCADE,
  unit_id         bigint NOT NULL REFERENCES units (unit_id) ON DELETE CASCADE,
  failure_mode    text REFERENCES failure_modes (failure_mode),
  analysis_id     uuid REFERENCES analyses (analysis_id) ON DELETE SET NULL,
  diagnosis_id    uuid REFERENCES diagnoses (diagnosis_id) ON DELETE SET NULL,
  detected_time   timestamptz NOT NULL DEFAULT now(),
  operating_hours double precision NOT NULL CHECK (operating_hours >= 0),
  confirmed       boolean NOT NULL,
  no_fault_found  boolean NOT NULL DEFAULT false,
  censored        boolean NOT NULL DEFAULT false,
  repaired        boolean NOT NULL DEFAULT false,
  repair_action   text NOT NULL DEFAULT '',
  notes           text NOT NULL DEFAULT '',
  record_time     timestamptz NOT NULL DEFAULT now(),
  CHECK (NOT (confirmed AND no_fault_found)),
  CHECK (NOT confirmed OR failure_mode IS NOT NULL)
);
CREATE INDEX failure_records_mode_idx ON failure_records (failure_mode, detected_time) WHERE confirmed;
CREATE INDEX failure_records_module_idx ON failure_records (module_id);
CREATE INDEX failure_records_unit_idx ON failure_records (unit_id, detected_time);
CREATE INDEX failure_records_list_idx ON failure_records (record_time DESC, record_id DESC);

-- Resolution of a diagnosis: the failure record it wrote.
ALTER TABLE diagnoses ADD COLUMN record_id uuid REFERENCES failure_records (record_id) ON DELETE SET NULL;

-- Fleet statistics that scan millions of rows are materialised; insdiagd
-- refreshes them periodically (--fleet-refresh-seconds) and the fleet
-- generator after writing.
CREATE MATERIALIZED VIEW fleet_counts AS
  SELECT coalesce(u.unit_type, '') AS unit_type,
         count(*) AS units,
         coalesce(sum(r.runs), 0)::bigint AS runs,
         coalesce(sum(a.analyses), 0)::bigint AS analyses,
         now() AS refreshed_time
    FROM units u
    LEFT JOIN (SELECT unit_id, count(*) AS runs FROM runs GROUP BY unit_id) r USING (unit_id)
    LEFT JOIN (SELECT unit_id, count(*) AS analyses FROM analyses GROUP BY unit_id) a USING (unit_id)
   GROUP BY coalesce(u.unit_type, '');
CREATE UNIQUE INDEX fleet_counts_idx ON fleet_counts (unit_type);

-- Identified parameters per unit type, parameter, batch and month.
CREATE MATERIALIZED VIEW parameter_trend_buckets AS
  SELECT coalesce(u.unit_type, '') AS unit_type,
         ip.parameter_id,
         coalesce(u.batch, '') AS batch,
         date_trunc('month', a.create_time) AS month,
         count(*) AS n,
         percentile_cont(0.5) WITHIN GROUP (ORDER BY ip.value) AS median,
         percentile_cont(0.25) WITHIN GROUP (ORDER BY ip.value) AS p25,
         percentile_cont(0.75) WITHIN GROUP (ORDER BY ip.value) AS p75,
         avg(ip.value) AS mean,
         now() AS refreshed_time
    FROM identified_parameters ip
    JOIN analyses a USING (analysis_id)
    JOIN units u ON u.unit_id = a.unit_id
   WHERE a.state = 'SUCCEEDED'
   GROUP BY 1, 2, 3, 4;
CREATE UNIQUE INDEX parameter_trend_buckets_idx
  ON parameter_trend_buckets (unit_type, parameter_id, batch, month);

-- Bench runs and their samples (shared/spec/bench-run-format.md).

-- Units under test. A run of an unknown serial registers its unit; the
-- knowledge base fills in type, modules and history later.
CREATE TABLE units (
  unit_id     bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  serial      text NOT NULL UNIQUE,
  unit_type   text,
  create_time timestamptz NOT NULL DEFAULT now()
);

CREATE TABLE runs (
  run_id              uuid PRIMARY KEY DEFAULT gen_random_uuid(),
  unit_id             bigint NOT NULL REFERENCES units (unit_id),
  format              text NOT NULL,
  unit_serial         text NOT NULL,
  unit_type           text,
  site_latitude_deg   double precision NOT NULL,
  site_longitude_deg  double precision NOT NULL,
  site_height_m       double precision NOT NULL,
  gyro_arw_rad_rts      double precision,
  gyro_bias_sigma_rad_s double precision,
  gyro_bias_tau_s       double precision,
  acc_vrw_mps_rts       double precision,
  acc_bias_sigma_mps2   double precision,
  acc_bias_tau_s        double precision,
  -- Free `# key: value` lines in file order: [["bench","table-3"], …].
  extra_metadata      jsonb NOT NULL DEFAULT '[]',
  has_temperature     boolean NOT NULL,
  sample_count        bigint NOT NULL CHECK (sample_count >= 0),
  nominal_interval_s  double precision NOT NULL,
  duration_s          double precision NOT NULL,
  first_t             double precision NOT NULL,
  -- The upload digest (proto/insdiag/v1/runs.proto, UploadRunRequest.sha256).
  sha256              text NOT NULL,
  -- Idempotency key of the upload and a fingerprint of what it carried, to
  -- tell a retry (same fingerprint) from a reused key (different one).
  request_id          text UNIQUE,
  request_fingerprint text,
  create_time         timestamptz NOT NULL DEFAULT now()
);
-- Keyset pagination, newest first.
CREATE INDEX runs_create_time_idx ON runs (create_time DESC, run_id DESC);
CREATE INDEX runs_unit_idx ON runs (unit_id);

-- Samples in chunks of consecutive samples: each chunk is the samples'
-- IEEE-754 binary64 little-endian values, t, gyro xyz, acc xyz, ref
-- roll/pitch/yaw[, temp], 80 or 88 bytes a sample. One row per sample would
-- cost ~100 bytes of row overhead per sample and minutes per million.
CREATE TABLE run_sample_chunks (
  run_id        uuid NOT NULL REFERENCES runs (run_id) ON DELETE CASCADE,
  chunk_index   integer NOT NULL,
  first_sample  bigint NOT NULL,
  sample_count  integer NOT NULL,
  data          bytea NOT NULL,
  PRIMARY KEY (run_id, chunk_index)
);
-- Float noise does not compress: skip TOAST's compression attempt.
ALTER TABLE run_sample_chunks ALTER COLUMN data SET STORAGE EXTERNAL;

-- Each unit type's diagnosis settings (docs/DIAGNOSIS.md; the fields of
-- insdiag.v1.DiagnosisSettings), from its failure-mode catalogue
-- (data/failure-modes/*.json), written when the catalogue is seeded and read
-- when a unit of the type is diagnosed and its modes' rates and signatures
-- are computed. A unit type without a row is diagnosed with INS-2000's
-- settings, and its diagnosis says so.
--
-- Existing databases: the table starts empty and fills at the server's next
-- start, which seeds the built-in catalogues; until then the fallback to
-- INS-2000's settings applies (and with no INS-2000 row either, diagnosing
-- is refused as FAILED_PRECONDITION rather than done with no settings).
CREATE TABLE diagnosis_settings (
  unit_type                  text PRIMARY KEY REFERENCES unit_types (unit_type) ON DELETE CASCADE,
  healthy_tolerance_sd       double precision NOT NULL,
  healthy_log_ratio_fraction double precision NOT NULL,
  healthy_z_sd               double precision NOT NULL,
  contamination              double precision NOT NULL,
  broad_log_ratio            double precision NOT NULL,
  broad_tolerance            double precision NOT NULL,
  broad_z                    double precision NOT NULL,
  unknown_prior              double precision NOT NULL,
  minimum_exposure_hours     double precision NOT NULL,
  expert_pseudo_hours        double precision NOT NULL,
  expert_signature_weight    double precision NOT NULL,
  significance_level         double precision NOT NULL,
  incidental_contamination   double precision NOT NULL,
  trend_z_change             double precision NOT NULL,
  trend_z_spread             double precision NOT NULL,
  present_score_octaves      integer NOT NULL,
  update_time                timestamptz NOT NULL DEFAULT now()
);

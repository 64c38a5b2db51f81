-- The FRACAS history is never lost: a correction of a failure record keeps
-- the version it replaces (KnowledgeService.CorrectFailureRecord). The
-- record's row holds its latest facts, so every count and statistic reads
-- current records as before; earlier versions are here, append-only.
ALTER TABLE failure_records ADD COLUMN revision integer NOT NULL DEFAULT 1;

CREATE TABLE failure_record_revisions (
  record_id       uuid NOT NULL REFERENCES failure_records (record_id) ON DELETE RESTRICT,
  revision        integer NOT NULL,
  failure_mode    text,
  detected_time   timestamptz NOT NULL,
  operating_hours double precision NOT NULL,
  confirmed       boolean NOT NULL,
  no_fault_found  boolean NOT NULL,
  censored        boolean NOT NULL,
  repaired        boolean NOT NULL,
  repair_action   text NOT NULL,
  notes           text NOT NULL,
  record_time     timestamptz NOT NULL,
  superseded_time timestamptz NOT NULL DEFAULT now(),
  reason          text NOT NULL CHECK (reason <> ''),
  PRIMARY KEY (record_id, revision)
);

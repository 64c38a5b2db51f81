-- Who may do what (proto/insdiag/v1/access.proto): bearer tokens, stored as
-- the SHA-256 of their secret, and the audit trail of every write.
CREATE TABLE access_tokens (
  token_id      uuid PRIMARY KEY DEFAULT gen_random_uuid(),
  display_name  text NOT NULL CHECK (display_name <> ''),
  role          text NOT NULL CHECK (role IN ('VIEWER', 'OPERATOR', 'ENGINEER', 'ADMIN')),
  secret_sha256 bytea NOT NULL UNIQUE CHECK (length(secret_sha256) = 32),
  creator       text NOT NULL,
  create_time   timestamptz NOT NULL DEFAULT now(),
  expire_time   timestamptz,
  revoke_time   timestamptz
);
CREATE INDEX access_tokens_list_idx ON access_tokens (create_time DESC, token_id DESC);

-- Append-only: nothing in insdiag updates or deletes an event.
CREATE TABLE audit_events (
  event_id     bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  event_time   timestamptz NOT NULL DEFAULT clock_timestamp(),
  token_id     uuid REFERENCES access_tokens (token_id),
  display_name text NOT NULL DEFAULT '',
  role         text NOT NULL DEFAULT '',
  method       text NOT NULL,
  resource     text NOT NULL DEFAULT '',
  peer         text NOT NULL DEFAULT '',
  code         text NOT NULL,
  message      text NOT NULL DEFAULT ''
);
CREATE INDEX audit_events_resource_idx ON audit_events (resource, event_id DESC);
CREATE INDEX audit_events_token_idx ON audit_events (token_id, event_id DESC);

-- The failure history is never deleted with a run: an analysis that a
-- diagnosis or a failure record rests on cannot be deleted (RunStore::Delete
-- refuses first, with a message; these keep the promise for any client).
ALTER TABLE diagnoses DROP CONSTRAINT diagnoses_analysis_id_fkey,
  ADD CONSTRAINT diagnoses_analysis_id_fkey FOREIGN KEY (analysis_id) REFERENCES analyses (analysis_id) ON DELETE RESTRICT;
ALTER TABLE failure_records DROP CONSTRAINT failure_records_analysis_id_fkey,
  ADD CONSTRAINT failure_records_analysis_id_fkey FOREIGN KEY (analysis_id) REFERENCES analyses (analysis_id) ON DELETE RESTRICT;

-- Exposure of the fleet's module roles, materialised (docs/FLEET.md,
-- docs/PERFORMANCE.md): summing every installed part's hours joins all the
-- fleet's modules with their units (100,000 parts for 10,000 units), which
-- took ~100 ms of GetFleetStatistics' 200 ms budget; exposure grows slowly,
-- so the statistics take it as of the views' last refresh (counts_time),
-- while failure counts stay live.
CREATE MATERIALIZED VIEW module_exposure AS
  SELECT coalesce(u.unit_type, '') AS unit_type,
         m.role,
         count(*) AS modules,
         sum(greatest(coalesce(m.removed_hours, u.operating_hours) - m.installed_hours, 0)) AS hours,
         now() AS refreshed_time
    FROM modules m
    JOIN units u USING (unit_id)
   GROUP BY 1, 2;
CREATE UNIQUE INDEX module_exposure_idx ON module_exposure (unit_type, role);

-- Failure counts per role read only the records that count (confirmed or
-- no fault found); censored records, most of a fleet's, are skipped.
CREATE INDEX failure_records_counted_idx ON failure_records (module_id)
  INCLUDE (unit_id, confirmed, no_fault_found) WHERE confirmed OR no_fault_found;

-- No query selects identified values by parameter alone (a parameter is 1/18
-- of the table: a sequential scan wins; ListParameterTrends walks analyses in
-- time order and probes the primary key), yet the index cost the fleet
-- generator's COPY of 18 million values ~45 s of maintenance.
DROP INDEX identified_parameters_parameter_idx;

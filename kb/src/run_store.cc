#include "insdiag/kb/run_store.h"

#include <absl/strings/str_cat.h>
#include <absl/time/time.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstring>
#include <map>
#include <numbers>

#include "insdiag/api/json_string.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

// Samples per stored chunk: ~700 KB rows keep TOAST efficient and let a
// reader stream a run without holding all of it.
constexpr std::size_t kSamplesPerChunk = 8192;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

std::size_t ValuesPerSample(bool has_temperature) { return has_temperature ? 11 : 10; }

void PutDouble(double value, std::string& out) {
  auto bits = std::bit_cast<std::uint64_t>(value);
  char bytes[8];
  for (char& byte : bytes) {
    byte = static_cast<char>(bits & 0xffU);
    bits >>= 8;
  }
  out.append(bytes, 8);
}

double GetDouble(const char* bytes) {
  std::uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = (bits << 8) | static_cast<unsigned char>(bytes[i]);
  return std::bit_cast<double>(bits);
}

// The storage encoding of migrations/0001_runs.sql.
std::string PackSamples(std::span<const engine::ImuSample> samples, bool has_temperature) {
  std::string out;
  out.reserve(samples.size() * ValuesPerSample(has_temperature) * 8);
  for (const auto& s : samples) {
    PutDouble(s.t_s, out);
    for (const auto* vec : {&s.gyro_rad_s, &s.acc_mps2, &s.ref_rpy_rad}) {
      for (int axis = 0; axis < 3; ++axis) PutDouble((*vec)[axis], out);
    }
    if (has_temperature) PutDouble(s.temp_degc, out);
  }
  return out;
}

absl::Status UnpackSamples(std::string_view bytes, bool has_temperature,
                           std::vector<engine::ImuSample>& out) {
  const std::size_t stride = ValuesPerSample(has_temperature) * 8;
  if (bytes.size() % stride != 0) return absl::DataLossError("a stored sample chunk has a partial sample");
  for (std::size_t offset = 0; offset < bytes.size(); offset += stride) {
    const char* p = bytes.data() + offset;
    engine::ImuSample s;
    s.t_s = GetDouble(p);
    for (int axis = 0; axis < 3; ++axis) {
      s.gyro_rad_s[axis] = GetDouble(p + 8 * (1 + axis));
      s.acc_mps2[axis] = GetDouble(p + 8 * (4 + axis));
      s.ref_rpy_rad[axis] = GetDouble(p + 8 * (7 + axis));
    }
    if (has_temperature) s.temp_degc = GetDouble(p + 80);
    out.push_back(s);
  }
  return absl::OkStatus();
}

// The free metadata, and a multi-position test's segment starts as the
// bench-run file holds them (`segment_starts`, format 2): stored as one more
// pair, read back into the typed field by LoadExtraMetadata.
std::string ExtraMetadataJson(const engine::BenchRunMetadata& metadata) {
  std::string out = "[";
  const auto append = [&out](std::string_view key, std::string_view value) {
    if (out.size() > 1) out += ',';
    absl::StrAppend(&out, "[", api::JsonString(key), ",", api::JsonString(value), "]");
  };
  if (!metadata.segment_starts.empty()) {
    append(benchrun::kSegmentStartsKey, benchrun::SegmentStartsText(metadata.segment_starts));
  }
  for (const auto& [key, value] : metadata.extra) append(key, value);
  return out + "]";
}

// When the run was tested: its `started_at` (ISO 8601 / RFC 3339) when that
// parses, so that a unit's history orders and spaces runs by when they were
// recorded; empty (NULL: the upload time stands in) for free text.
std::string TestTimeText(const engine::BenchRunMetadata& metadata) {
  const std::optional<std::string> started = metadata.Extra("started_at");
  if (!started.has_value()) return {};
  absl::Time time;
  std::string error;
  if (!absl::ParseTime(absl::RFC3339_full, *started, &time, &error)) return {};
  return absl::FormatTime(absl::RFC3339_full, time, absl::UTCTimeZone());
}

// Rejects what PostgreSQL's uuid input would reject, so that a malformed
// name is the caller's INVALID_ARGUMENT, not our INTERNAL.
absl::Status CheckRunId(const std::string& run_id) {
  const bool shaped = run_id.size() == 36 && std::all_of(run_id.begin(), run_id.end(), [](char c) {
                        return std::isxdigit(static_cast<unsigned char>(c)) || c == '-';
                      });
  if (!shaped) return absl::InvalidArgumentError(absl::StrCat("'", run_id, "' is not a run id (a UUID)"));
  return absl::OkStatus();
}

constexpr char kRunColumns[] =
    "run_id::text, format, unit_serial, coalesce(unit_type, ''), site_latitude_deg, "
    "site_longitude_deg, site_height_m, gyro_arw_rad_rts, gyro_bias_sigma_rad_s, gyro_bias_tau_s, "
    "acc_vrw_mps_rts, acc_bias_sigma_mps2, acc_bias_tau_s, has_temperature, sample_count, "
    "nominal_interval_s, duration_s, first_t, sha256, coalesce(request_id, ''), "
    "(extract(epoch FROM create_time) * 1000000)::bigint, create_time::text";

// Reads one row selected with kRunColumns.
absl::StatusOr<StoredRun> RunFromRow(const Result& rows, int row) {
  StoredRun run;
  run.id = rows.String(row, 0);
  run.metadata.format = rows.String(row, 1);
  run.metadata.unit_serial = rows.String(row, 2);
  run.metadata.unit_type = rows.String(row, 3);
  const std::array<double*, 3> site = {&run.metadata.site.latitude_rad, &run.metadata.site.longitude_rad,
                                       &run.metadata.site.height_m};
  for (int i = 0; i < 3; ++i) {
    INSDIAG_ASSIGN_OR_RETURN(auto value, rows.Double(row, 4 + i));
    *site[i] = value;
  }
  run.metadata.site.latitude_rad /= kDegPerRad;
  run.metadata.site.longitude_rad /= kDegPerRad;
  auto& sheet = run.metadata.datasheet;
  const std::array<std::optional<double>*, 6> datasheet = {
      &sheet.gyro_arw_rad_rts, &sheet.gyro_bias_sigma_rad_s, &sheet.gyro_bias_tau_s,
      &sheet.acc_vrw_mps_rts,  &sheet.acc_bias_sigma_mps2,   &sheet.acc_bias_tau_s};
  for (int i = 0; i < 6; ++i) *datasheet[i] = rows.OptionalDouble(row, 7 + i);
  run.has_temperature = rows.Bool(row, 13);
  auto count = rows.Int(row, 14);
  auto interval = rows.Double(row, 15);
  auto duration = rows.Double(row, 16);
  auto first_t = rows.Double(row, 17);
  auto created = rows.Int(row, 20);
  for (const absl::Status& status :
       {count.status(), interval.status(), duration.status(), first_t.status(), created.status()}) {
    if (!status.ok()) return status;
  }
  run.sample_count = *count;
  run.nominal_interval_s = *interval;
  run.duration_s = *duration;
  run.first_t_s = *first_t;
  run.sha256 = rows.String(row, 18);
  run.request_id = rows.String(row, 19);
  run.create_time_unix_us = *created;
  return run;
}

// Fills in the free metadata of `runs` (stored as jsonb pairs) in one query.
absl::Status LoadExtraMetadata(Connection& db, std::vector<StoredRun>& runs) {
  if (runs.empty()) return absl::OkStatus();
  std::string ids = "{";
  std::map<std::string, StoredRun*> by_id;
  for (auto& run : runs) {
    if (ids.size() > 1) ids += ',';
    ids += run.id;
    by_id[run.id] = &run;
  }
  ids += '}';
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec("SELECT r.run_id::text, e.pair->>0, e.pair->>1 FROM runs r, "
              "jsonb_array_elements(r.extra_metadata) WITH ORDINALITY AS e(pair, position) "
              "WHERE r.run_id = ANY($1::uuid[]) ORDER BY r.run_id, e.position",
              {Param::Text(ids)}));
  for (int row = 0; row < rows.rows(); ++row) {
    engine::BenchRunMetadata& metadata = by_id[rows.String(row, 0)]->metadata;
    if (rows.String(row, 1) == benchrun::kSegmentStartsKey) {
      auto starts = benchrun::ParseSegmentStarts(rows.String(row, 2));
      if (!starts.ok()) return absl::DataLossError("a stored run's segment starts: " + std::string(starts.status().message()));
      metadata.segment_starts = *std::move(starts);
      continue;
    }
    metadata.extra.emplace_back(rows.String(row, 1), rows.String(row, 2));
  }
  return absl::OkStatus();
}

absl::StatusOr<StoredRun> GetRun(Connection& db, const std::string& run_id) {
  INSDIAG_RETURN_IF_ERROR(CheckRunId(run_id));
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db.Exec(absl::StrCat("SELECT ", kRunColumns, " FROM runs WHERE run_id = $1::uuid"),
                         {Param::Text(run_id)}));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kRuns, run_id), " does not exist"));
  std::vector<StoredRun> runs;
  INSDIAG_ASSIGN_OR_RETURN(auto run, RunFromRow(rows, 0));
  runs.push_back(std::move(run));
  INSDIAG_RETURN_IF_ERROR(LoadExtraMetadata(db, runs));
  return std::move(runs.front());
}

absl::StatusOr<std::string> InsertRun(Connection& db, const engine::BenchRun& run,
                                      const UploadIdentity& identity) {
  const auto& meta = run.metadata;
  INSDIAG_ASSIGN_OR_RETURN(
      auto unit, db.Exec("INSERT INTO units (serial, unit_type) VALUES ($1, $2) "
                         "ON CONFLICT (serial) DO UPDATE SET unit_type = coalesce(units.unit_type, "
                         "EXCLUDED.unit_type) "
                         "RETURNING unit_id",
                         {Param::Text(meta.unit_serial), Param::TextOrNull(meta.unit_type)}));
  // A unit's modules are registered with it (migrations/0002_knowledge.sql):
  // one current part per role, its serial unknown until the knowledge base learns it.
  INSDIAG_RETURN_IF_ERROR(
      db.Exec("INSERT INTO modules (unit_id, role, installed_time) "
              "SELECT u.unit_id, r.role, u.create_time FROM units u CROSS JOIN module_roles r "
              "WHERE u.unit_id = $1 AND NOT EXISTS (SELECT 1 FROM modules m WHERE m.unit_id = "
              "u.unit_id "
              "AND m.role = r.role AND m.removed_time IS NULL)",
              {Param::Text(unit.String(0, 0))}));

  const auto& sheet = meta.datasheet;
  auto inserted = db.Exec(
      "INSERT INTO runs (unit_id, format, unit_serial, unit_type, site_latitude_deg, "
      "site_longitude_deg, site_height_m, gyro_arw_rad_rts, gyro_bias_sigma_rad_s, "
      "gyro_bias_tau_s, "
      "acc_vrw_mps_rts, acc_bias_sigma_mps2, acc_bias_tau_s, extra_metadata, has_temperature, "
      "sample_count, nominal_interval_s, duration_s, first_t, sha256, request_id, "
      "request_fingerprint, test_time) "
      "VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14::jsonb, $15, $16, $17, "
      "$18, "
      "$19, $20, $21, $22, $23::timestamptz) RETURNING run_id::text",
      {Param::Text(unit.String(0, 0)),
       Param::Text(meta.format),
       Param::Text(meta.unit_serial),
       Param::TextOrNull(meta.unit_type),
       Param::Double(meta.site.latitude_rad * kDegPerRad),
       Param::Double(meta.site.longitude_rad * kDegPerRad),
       Param::Double(meta.site.height_m),
       Param::OptionalDouble(sheet.gyro_arw_rad_rts),
       Param::OptionalDouble(sheet.gyro_bias_sigma_rad_s),
       Param::OptionalDouble(sheet.gyro_bias_tau_s),
       Param::OptionalDouble(sheet.acc_vrw_mps_rts),
       Param::OptionalDouble(sheet.acc_bias_sigma_mps2),
       Param::OptionalDouble(sheet.acc_bias_tau_s),
       Param::Text(ExtraMetadataJson(meta)),
       Param::Text(run.has_temperature ? "true" : "false"),
       Param::Int(static_cast<std::int64_t>(run.samples.size())),
       Param::Double(run.NominalIntervalS()),
       Param::Double(run.DurationS()),
       Param::Double(run.samples.empty() ? 0.0 : run.samples.front().t_s),
       Param::Text(identity.sha256),
       Param::TextOrNull(identity.request_id),
       Param::TextOrNull(identity.request_fingerprint),
       Param::TextOrNull(TestTimeText(meta))});
  if (!inserted.ok()) return inserted.status();
  const std::string run_id = inserted->String(0, 0);

  const std::span<const engine::ImuSample> samples(run.samples);
  for (std::size_t first = 0, chunk = 0; first < samples.size(); first += kSamplesPerChunk, ++chunk) {
    const auto part = samples.subspan(first, std::min(kSamplesPerChunk, samples.size() - first));
    INSDIAG_RETURN_IF_ERROR(db.Exec(
        "INSERT INTO run_sample_chunks (run_id, chunk_index, first_sample, sample_count, data) "
        "VALUES ($1::uuid, $2, $3, $4, $5)",
        {Param::Text(run_id), Param::Int(static_cast<std::int64_t>(chunk)),
         Param::Int(static_cast<std::int64_t>(first)),
         Param::Int(static_cast<std::int64_t>(part.size())),
         Param::Bytes(PackSamples(part, run.has_temperature))}));
  }
  return run_id;
}

}  // namespace

absl::StatusOr<StoredRun> RunStore::Create(const engine::BenchRun& run, const UploadIdentity& identity) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  absl::StatusOr<StoredRun> result = absl::InternalError("run not stored");
  const absl::Status status = db->InTransaction([&]() -> absl::Status {
    if (!identity.request_id.empty()) {
      // Serialise uploads of one request id: a retry racing the original
      // waits for it and then finds its run.
      INSDIAG_RETURN_IF_ERROR(
          db->Exec("SELECT pg_advisory_xact_lock($1)",
                   {Param::Int(AdvisoryLockKey("insdiag.run." + identity.request_id))}));
      INSDIAG_ASSIGN_OR_RETURN(auto earlier,
                               db->Exec("SELECT run_id::text, coalesce(request_fingerprint, '') "
                                        "FROM runs WHERE request_id = $1",
                                        {Param::Text(identity.request_id)}));
      if (earlier.rows() > 0) {
        if (earlier.Get(0, 1) != identity.request_fingerprint) {
          return absl::AlreadyExistsError(absl::StrCat(
              "request id '", identity.request_id, "' was already used to upload runs/",
              earlier.String(0, 0), " with different content"));
        }
        result = GetRun(*db, earlier.String(0, 0));
        return result.status();
      }
    }
    INSDIAG_ASSIGN_OR_RETURN(auto run_id, InsertRun(*db, run, identity));
    result = GetRun(*db, run_id);
    return result.status();
  });
  if (!status.ok()) return status;
  return result;
}

absl::StatusOr<StoredRun> RunStore::Get(const std::string& run_id) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  return GetRun(*db, run_id);
}

absl::StatusOr<RunPage> RunStore::List(const RunQuery& query) {
  const int page_size = internal::ClampPageSize(query.page_size);
  std::vector<Param> params = {Param::Int(page_size + 1), Param::TextOrNull(query.unit_serial)};
  // Page tokens are opaque to clients: the last row's sort key (store_util.h).
  INSDIAG_ASSIGN_OR_RETURN(const std::string after,
                           internal::KeysetCondition(query.page_token, "create_time", "run_id",
                                                     internal::KeysetOrder::kNewestFirst, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(absl::StrCat("SELECT ", kRunColumns,
                            " FROM runs WHERE ($2::text IS NULL OR unit_serial = $2) AND ", after,
                            " ORDER BY create_time DESC, run_id DESC LIMIT $1"),
               params));
  RunPage page;
  const int shown = std::min(rows.rows(), page_size);
  for (int row = 0; row < shown; ++row) {
    INSDIAG_ASSIGN_OR_RETURN(auto run, RunFromRow(rows, row));
    page.runs.push_back(std::move(run));
  }
  // One row more than asked for tells whether another page exists.
  if (rows.rows() > page_size) {
    page.next_page_token = internal::EncodeToken(rows.String(shown - 1, 21), page.runs.back().id);
  }
  if (query.with_extra_metadata) INSDIAG_RETURN_IF_ERROR(LoadExtraMetadata(*db, page.runs));
  return page;
}

absl::Status RunStore::Delete(const std::string& run_id) {
  INSDIAG_RETURN_IF_ERROR(CheckRunId(run_id));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  return db->InTransaction([&]() -> absl::Status {
    // A diagnosis that lands between the check and the delete is refused by
    // the foreign keys (migrations/0004_access.sql): the check gives the message.
    INSDIAG_ASSIGN_OR_RETURN(
        auto run,
        db->Exec("SELECT 1 FROM runs WHERE run_id = $1::uuid FOR UPDATE", {Param::Text(run_id)}));
    if (run.rows() == 0)
      return absl::NotFoundError(
          absl::StrCat(api::ResourceName(api::kRuns, run_id), " does not exist"));
    INSDIAG_ASSIGN_OR_RETURN(auto history,
                             db->Exec("SELECT (SELECT count(*) FROM diagnoses d JOIN analyses a "
                                      "USING (analysis_id) WHERE a.run_id = $1::uuid), "
                                      "(SELECT count(*) FROM failure_records f JOIN analyses a "
                                      "USING (analysis_id) WHERE a.run_id = $1::uuid)",
                                      {Param::Text(run_id)}));
    const std::string diagnoses = history.String(0, 0), records = history.String(0, 1);
    if (diagnoses != "0" || records != "0") {
      return absl::FailedPreconditionError(absl::StrCat(
          api::ResourceName(api::kRuns, run_id), " is not deleted: ", diagnoses, " diagnoses and ",
          records, " failure records rest on its analyses, and the failure history is kept"));
    }
    return db->Exec("DELETE FROM runs WHERE run_id = $1::uuid", {Param::Text(run_id)}).status();
  });
}

absl::Status RunStore::ReadSamples(const std::string& run_id, std::size_t batch_samples,
                                   absl::FunctionRef<bool(std::span<const engine::ImuSample>)> consume) {
  INSDIAG_ASSIGN_OR_RETURN(auto run, Get(run_id));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  batch_samples = std::max<std::size_t>(batch_samples, 1);
  // Enough stored chunks per query to fill about one batch.
  const std::int64_t chunks_per_query =
      static_cast<std::int64_t>(std::max<std::size_t>(1, batch_samples / kSamplesPerChunk + 1));
  std::vector<engine::ImuSample> pending;
  std::int64_t next_chunk = 0;
  for (;;) {
    INSDIAG_ASSIGN_OR_RETURN(
        auto rows,
        db->Exec("SELECT data FROM run_sample_chunks WHERE run_id = $1::uuid AND chunk_index >= $2 "
                 "ORDER BY chunk_index LIMIT $3",
                 {Param::Text(run.id), Param::Int(next_chunk), Param::Int(chunks_per_query)},
                 ResultFormat::kBinary));
    for (int row = 0; row < rows.rows(); ++row) {
      if (auto status = UnpackSamples(rows.Get(row, 0), run.has_temperature, pending);
          !status.ok()) {
        return status;
      }
    }
    next_chunk += rows.rows();
    const bool last = rows.rows() < chunks_per_query;
    std::size_t sent = 0;
    while (pending.size() - sent >= batch_samples || (last && sent < pending.size())) {
      const std::size_t count = std::min(batch_samples, pending.size() - sent);
      if (!consume(std::span<const engine::ImuSample>(pending).subspan(sent, count))) return absl::OkStatus();
      sent += count;
    }
    pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(sent));
    if (last) return absl::OkStatus();
  }
}

}  // namespace insdiag::kb

#include "insdiag/kb/analysis_store.h"

#include <absl/strings/escaping.h>
#include <absl/strings/str_cat.h>

#include <bit>
#include <cmath>
#include <set>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/filter/observation.h"
#include "report_rows.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::Micros;

constexpr char kColumns[] =
    "a.analysis_id::text, a.run_id::text, a.state, encode(a.request, 'hex'), a.progress_fraction, a.progress_stage, "
    "coalesce(a.error_code, 0), coalesce(a.error_message, ''), a.attempts, u.serial, ";

std::string SelectAnalyses(bool include_report) {
  return absl::StrCat("SELECT ", kColumns, Micros("a.create_time"), ", ", Micros("a.update_time"), ", ",
                      include_report ? "encode(a.report, 'hex')" : "NULL::text",
                      ", a.create_time::text FROM analyses a JOIN units u ON u.unit_id = a.unit_id ");
}

AnalysisState StateOf(std::string_view text) {
  for (const AnalysisState state : {AnalysisState::kQueued, AnalysisState::kRunning, AnalysisState::kSucceeded,
                                    AnalysisState::kFailed, AnalysisState::kCancelled}) {
    if (text == AnalysisStateName(state)) return state;
  }
  return AnalysisState::kUnspecified;
}

Analysis AnalysisFromRow(const Result& rows, int row) {
  Analysis a;
  a.name = api::ResourceName(api::kAnalyses, rows.String(row, 0));
  a.run = api::ResourceName(api::kRuns, rows.String(row, 1));
  // bytea travels as hex text here: the rest of the row is text.
  a.encoded_spec = absl::HexStringToBytes(rows.String(row, 3));
  a.state = StateOf(rows.Get(row, 2));
  a.progress_fraction = internal::DoubleOr0(rows, row, 4);
  a.progress_stage = rows.String(row, 5);
  if (a.state == AnalysisState::kFailed) {
    a.error = AnalysisError{static_cast<int>(internal::IntOr0(rows, row, 6)), rows.String(row, 7)};
  }
  a.attempts = static_cast<int>(internal::IntOr0(rows, row, 8));
  a.unit = api::ResourceName(api::kUnits, rows.String(row, 9));
  a.create_time = absl::FromUnixMicros(internal::IntOr0(rows, row, 10));
  a.update_time = absl::FromUnixMicros(internal::IntOr0(rows, row, 11));
  if (!rows.IsNull(row, 12)) {
    a.report = StoredReport{absl::HexStringToBytes(rows.String(row, 12)), ReportRows()};
  }
  return a;
}

// A SUCCEEDED analysis stored without its report bytes (generated fleet
// history) has its report's rows instead.
absl::Status CompleteReport(Connection& db, const Result& rows, int row, Analysis& analysis) {
  if (analysis.state != AnalysisState::kSucceeded || !rows.IsNull(row, 12)) return absl::OkStatus();
  auto report_rows = internal::ReadReportRows(db, rows.String(row, 0));
  if (!report_rows.ok()) return report_rows.status();
  analysis.report = StoredReport{std::nullopt, *std::move(report_rows)};
  return absl::OkStatus();
}

absl::Status CheckId(const std::string& id) {
  if (!internal::IsUuid(id)) return absl::InvalidArgumentError(absl::StrCat("'", id, "' is not an analysis id (a UUID)"));
  return absl::OkStatus();
}

double Finite(double v) { return std::isfinite(v) ? v : 0.0; }

std::string Millis(std::chrono::milliseconds d) { return std::to_string(d.count()); }

void PutDouble(double value, std::string& out) {
  auto bits = std::bit_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i, bits >>= 8) out.push_back(static_cast<char>(bits & 0xffU));
}

double GetDouble(const char* bytes) {
  std::uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = (bits << 8) | static_cast<unsigned char>(bytes[i]);
  return std::bit_cast<double>(bits);
}

// The series as stored: K time values, then per channel (engine order) K
// measured, K predicted, K residual, K σ values, float64 little-endian.
std::string PackSeries(const engine::AnalysisSeries& s) {
  const std::size_t k = s.time_s.size();
  std::string out;
  out.reserve(8 * k * (1 + 4 * engine::kChannelCount));
  for (double t : s.time_s) PutDouble(t, out);
  for (int c = 0; c < engine::kChannelCount; ++c) {
    for (const Eigen::MatrixXd* m : {&s.measured, &s.predicted, &s.residual, &s.sigma}) {
      for (std::size_t e = 0; e < k; ++e) PutDouble((*m)(static_cast<Eigen::Index>(e), c), out);
    }
  }
  return out;
}

}  // namespace

absl::StatusOr<Analysis> AnalysisStore::Create(const std::string& run_id, const std::string& encoded_spec,
                                               const std::string& request_id, int max_attempts) {
  if (!internal::IsUuid(run_id)) return absl::InvalidArgumentError(absl::StrCat("analysis.run: '", run_id, "' is not a run id"));
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  const std::string fingerprint = absl::StrCat(run_id, "|", absl::BytesToHexString(encoded_spec));
  std::string id;
  const absl::Status status = (*db)->InTransaction([&]() -> absl::Status {
    if (!request_id.empty()) {
      auto locked = (*db)->Exec("SELECT pg_advisory_xact_lock($1)",
                                {Param::Int(AdvisoryLockKey("insdiag.analysis." + request_id))});
      if (!locked.ok()) return locked.status();
      auto earlier = (*db)->Exec("SELECT analysis_id::text, request_fingerprint FROM analyses WHERE request_id = $1",
                                 {Param::Text(request_id)});
      if (!earlier.ok()) return earlier.status();
      if (earlier->rows() > 0) {
        if (earlier->String(0, 1) != fingerprint) {
          return absl::AlreadyExistsError(absl::StrCat("request id '", request_id, "' was already used for analyses/",
                                                       earlier->String(0, 0), " of another run or model"));
        }
        id = earlier->String(0, 0);
        return absl::OkStatus();
      }
    }
    auto inserted = (*db)->Exec(
        "INSERT INTO analyses (run_id, unit_id, request, request_id, request_fingerprint, max_attempts, unit_hours) "
        "SELECT r.run_id, r.unit_id, $2, $3, $4, $5, u.operating_hours FROM runs r JOIN units u USING (unit_id) "
        "WHERE r.run_id = $1::uuid RETURNING analysis_id::text",
        {Param::Text(run_id), Param::Bytes(encoded_spec), Param::TextOrNull(request_id),
         Param::TextOrNull(request_id.empty() ? "" : fingerprint), Param::Int(max_attempts)});
    if (!inserted.ok()) return inserted.status();
    if (inserted->rows() == 0)
      return absl::NotFoundError(
          absl::StrCat(api::ResourceName(api::kRuns, run_id), " does not exist"));
    id = inserted->String(0, 0);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  auto rows = (*db)->Exec(SelectAnalyses(false) + "WHERE a.analysis_id = $1::uuid", {Param::Text(id)});
  if (!rows.ok()) return rows.status();
  return AnalysisFromRow(*rows, 0);
}

absl::StatusOr<Analysis> AnalysisStore::Get(const std::string& analysis_id, bool include_report) {
  if (auto s = CheckId(analysis_id); !s.ok()) return s;
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(SelectAnalyses(include_report) + "WHERE a.analysis_id = $1::uuid",
                          {Param::Text(analysis_id)}, ResultFormat::kText);
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kAnalyses, analysis_id), " does not exist"));
  Analysis analysis = AnalysisFromRow(*rows, 0);
  if (include_report) {
    if (auto s = CompleteReport(**db, *rows, 0, analysis); !s.ok()) return s;
  }
  return analysis;
}

absl::StatusOr<AnalysisPage> AnalysisStore::List(const AnalysisQuery& query) {
  const int page_size = internal::ClampPageSize(query.page_size);
  if (!query.run_id.empty() && !internal::IsUuid(query.run_id)) {
    return absl::InvalidArgumentError(absl::StrCat("run: '", query.run_id, "' is not a run id"));
  }
  std::vector<Param> params = {Param::Int(page_size + 1), Param::TextOrNull(query.run_id),
                               Param::TextOrNull(query.unit_serial)};
  auto after = internal::KeysetCondition(query.page_token, "a.create_time", "a.analysis_id",
                                         internal::KeysetOrder::kNewestFirst, params);
  if (!after.ok()) return after.status();
  auto db = list_pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      absl::StrCat(SelectAnalyses(query.include_reports),
                   "WHERE ($2::uuid IS NULL OR a.run_id = $2::uuid) AND ($3::text IS NULL OR u.serial = $3) AND ",
                   *after, " ORDER BY a.create_time DESC, a.analysis_id DESC LIMIT $1"),
      params);
  if (!rows.ok()) return rows.status();
  AnalysisPage page;
  const int shown = std::min(rows->rows(), page_size);
  for (int row = 0; row < shown; ++row) {
    page.analyses.push_back(AnalysisFromRow(*rows, row));
    if (query.include_reports) {
      if (auto s = CompleteReport(**db, *rows, row, page.analyses.back()); !s.ok()) return s;
    }
  }
  if (rows->rows() > page_size) {
    page.next_page_token = internal::EncodeToken(rows->String(shown - 1, 13), rows->String(shown - 1, 0));
  }
  return page;
}

absl::StatusOr<QueueStats> AnalysisStore::Queue() {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      "SELECT count(*) FILTER (WHERE state = 'QUEUED'), count(*) FILTER (WHERE state = 'RUNNING'), "
      "coalesce(extract(epoch FROM now() - min(create_time) FILTER (WHERE state = 'QUEUED')), 0)::float8 "
      "FROM analyses WHERE state IN ('QUEUED', 'RUNNING')");
  if (!rows.ok()) return rows.status();
  QueueStats stats;
  stats.queued = internal::IntOr0(*rows, 0, 0);
  stats.running = internal::IntOr0(*rows, 0, 1);
  stats.oldest_queued_age_s = internal::DoubleOr0(*rows, 0, 2);
  return stats;
}

absl::StatusOr<std::optional<ClaimedJob>> AnalysisStore::Claim(const std::string& owner,
                                                               std::chrono::milliseconds lease) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  // One statement: the row is locked, skipped by concurrent claimers, and
  // updated before the lock is released at commit.
  auto rows = (*db)->Exec(
      "UPDATE analyses SET state = 'RUNNING', lease_owner = $1, lease_expires = now() + $2 * interval '1 millisecond', "
      "attempts = attempts + 1, update_time = now(), start_time = coalesce(start_time, now()), "
      "progress_fraction = 0, progress_stage = 'queued for the engine' "
      "WHERE analysis_id = (SELECT analysis_id FROM analyses WHERE state = 'QUEUED' ORDER BY create_time "
      "FOR UPDATE SKIP LOCKED LIMIT 1) "
      "RETURNING analysis_id::text, run_id::text, encode(request, 'hex'), attempts",
      {Param::Text(owner), Param::Text(Millis(lease))});
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return std::optional<ClaimedJob>();
  ClaimedJob job;
  job.analysis_id = rows->String(0, 0);
  job.run_id = rows->String(0, 1);
  job.encoded_spec = absl::HexStringToBytes(rows->String(0, 2));
  job.attempt = static_cast<int>(internal::IntOr0(*rows, 0, 3));
  return std::optional<ClaimedJob>(std::move(job));
}

absl::StatusOr<LeaseState> AnalysisStore::Heartbeat(const std::string& analysis_id, const std::string& owner,
                                                    std::chrono::milliseconds lease) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      "UPDATE analyses SET lease_expires = now() + $3 * interval '1 millisecond' "
      "WHERE analysis_id = $1::uuid AND state = 'RUNNING' AND lease_owner = $2 RETURNING cancel_requested",
      {Param::Text(analysis_id), Param::Text(owner), Param::Text(Millis(lease))});
  if (!rows.ok()) return rows.status();
  LeaseState state;
  state.owned = rows->rows() > 0;
  state.cancel_requested = state.owned && rows->Bool(0, 0);
  return state;
}

absl::StatusOr<LeaseState> AnalysisStore::UpdateProgress(const std::string& analysis_id, const std::string& owner,
                                                         double fraction, const std::string& stage,
                                                         std::chrono::milliseconds lease) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      "UPDATE analyses SET progress_fraction = $3, progress_stage = $4, update_time = now(), "
      "lease_expires = now() + $5 * interval '1 millisecond' "
      "WHERE analysis_id = $1::uuid AND state = 'RUNNING' AND lease_owner = $2 RETURNING cancel_requested",
      {Param::Text(analysis_id), Param::Text(owner), Param::Double(std::clamp(fraction, 0.0, 1.0)),
       Param::Text(stage), Param::Text(Millis(lease))});
  if (!rows.ok()) return rows.status();
  LeaseState state;
  state.owned = rows->rows() > 0;
  state.cancel_requested = state.owned && rows->Bool(0, 0);
  return state;
}

absl::Status AnalysisStore::Complete(const std::string& analysis_id, const std::string& owner,
                                     const std::string& encoded_report, const ReportRows& rows,
                                     const engine::AnalysisSeries* series) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  return (*db)->InTransaction([&]() -> absl::Status {
    auto updated = (*db)->Exec(
        "UPDATE analyses SET state = 'SUCCEEDED', report = $3, verdict = $4, nis_mean = $5, log_likelihood = $6, "
        "aic = $7, bic = $8, progress_fraction = 1, progress_stage = 'done', lease_owner = NULL, "
        "lease_expires = NULL, update_time = now(), end_time = now() "
        "WHERE analysis_id = $1::uuid AND state = 'RUNNING' AND lease_owner = $2",
        {Param::Text(analysis_id), Param::Text(owner), Param::Bytes(encoded_report),
         rows.verdict.has_value() ? Param::Text(engine::VerdictName(*rows.verdict)) : Param::Null(),
         Param::Double(Finite(rows.nis_mean)), Param::Double(Finite(rows.log_likelihood)),
         Param::Double(Finite(rows.aic)), Param::Double(Finite(rows.bic))});
    if (!updated.ok()) return updated.status();
    if (updated->AffectedRows() == 0) {
      return absl::FailedPreconditionError(
          absl::StrCat(api::ResourceName(api::kAnalyses, analysis_id), " is no longer held by ",
                       owner, " (lease lost or cancelled)"));
    }
    if (auto s = internal::WriteReportRows(**db, analysis_id, rows); !s.ok()) return s;
    if (series != nullptr && !series->time_s.empty()) {
      auto stored = (*db)->Exec("INSERT INTO analysis_series (analysis_id, epochs, data) VALUES ($1::uuid, $2, $3)",
                                {Param::Text(analysis_id), Param::Int(static_cast<std::int64_t>(series->time_s.size())),
                                 Param::Bytes(PackSeries(*series))});
      if (!stored.ok()) return stored.status();
    }
    return absl::OkStatus();
  });
}

absl::Status AnalysisStore::Fail(const std::string& analysis_id, const std::string& owner, const absl::Status& error,
                                 bool retry) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto updated = (*db)->Exec(
      "UPDATE analyses SET state = CASE WHEN $3 AND attempts < max_attempts THEN 'QUEUED' ELSE 'FAILED' END, "
      "error_code = $4, error_message = $5, lease_owner = NULL, lease_expires = NULL, update_time = now(), "
      "end_time = CASE WHEN $3 AND attempts < max_attempts THEN NULL ELSE now() END "
      "WHERE analysis_id = $1::uuid AND state = 'RUNNING' AND lease_owner = $2",
      {Param::Text(analysis_id), Param::Text(owner), Param::Text(retry ? "true" : "false"),
       Param::Int(static_cast<int>(error.code())), Param::Text(std::string(error.message()))});
  return updated.status();
}

absl::Status AnalysisStore::MarkCancelled(const std::string& analysis_id, const std::string& owner) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  return (*db)
      ->Exec("UPDATE analyses SET state = 'CANCELLED', lease_owner = NULL, lease_expires = NULL, update_time = now(), "
             "end_time = now(), progress_stage = 'cancelled' "
             "WHERE analysis_id = $1::uuid AND state = 'RUNNING' AND lease_owner = $2",
             {Param::Text(analysis_id), Param::Text(owner)})
      .status();
}

absl::StatusOr<ReapReport> AnalysisStore::Reap() {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      "UPDATE analyses SET "
      "state = CASE WHEN cancel_requested THEN 'CANCELLED' WHEN attempts < max_attempts THEN 'QUEUED' ELSE 'FAILED' END, "
      "error_code = CASE WHEN attempts < max_attempts OR cancel_requested THEN error_code ELSE 4 END, "
      "error_message = CASE WHEN attempts < max_attempts OR cancel_requested THEN error_message "
      "  ELSE 'the worker running this analysis stopped ' || attempts || ' times (lease expired)' END, "
      "progress_stage = CASE WHEN attempts < max_attempts THEN 'requeued: worker ' || lease_owner || ' stopped' "
      "  ELSE progress_stage END, "
      "lease_owner = NULL, lease_expires = NULL, update_time = now() "
      "WHERE analysis_id IN (SELECT analysis_id FROM analyses WHERE state = 'RUNNING' AND lease_expires < now() "
      "FOR UPDATE SKIP LOCKED) RETURNING state");
  if (!rows.ok()) return rows.status();
  ReapReport report;
  for (int row = 0; row < rows->rows(); ++row) {
    if (rows->Get(row, 0) == "QUEUED") ++report.requeued;
    else ++report.failed;
  }
  return report;
}

absl::StatusOr<Analysis> AnalysisStore::Cancel(const std::string& analysis_id) {
  if (auto s = CheckId(analysis_id); !s.ok()) return s;
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto updated = (*db)->Exec(
      "UPDATE analyses SET state = CASE WHEN state = 'QUEUED' THEN 'CANCELLED' ELSE state END, "
      "cancel_requested = (state = 'RUNNING'), update_time = now(), "
      "end_time = CASE WHEN state = 'QUEUED' THEN now() ELSE end_time END "
      "WHERE analysis_id = $1::uuid AND state IN ('QUEUED', 'RUNNING')",
      {Param::Text(analysis_id)});
  if (!updated.ok()) return updated.status();
  return Get(analysis_id, false);
}

absl::Status AnalysisStore::ReadSeries(const std::string& analysis_id, const std::vector<std::string>& channels,
                                       std::size_t chunk_points,
                                       absl::FunctionRef<bool(std::span<const ResidualPoint>)> consume) {
  auto analysis = Get(analysis_id, false);
  if (!analysis.ok()) return analysis.status();
  if (analysis->state != AnalysisState::kSucceeded) {
    return absl::FailedPreconditionError(absl::StrCat(analysis->name, " is ", AnalysisStateName(analysis->state),
                                                      "; its series exist once it SUCCEEDED"));
  }
  std::set<std::string> wanted(channels.begin(), channels.end());
  for (const auto& c : wanted) {
    bool known = false;
    for (auto name : engine::kChannelNames) known = known || name == c;
    if (!known) return absl::InvalidArgumentError(absl::StrCat("channels: '", c, "' is not an observation channel"));
  }
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec("SELECT epochs, data FROM analysis_series WHERE analysis_id = $1::uuid",
                          {Param::Text(analysis_id)}, ResultFormat::kBinary);
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::OkStatus();  // an analysis without series (e.g. generated history)
  const std::string_view epochs_raw = rows->Get(0, 0);
  std::uint32_t epochs = 0;  // binary int4, big-endian
  for (char c : epochs_raw) epochs = (epochs << 8) | static_cast<unsigned char>(c);
  const std::string_view data = rows->Get(0, 1);
  const std::size_t k = epochs;
  // Series stored before the attitude channels hold the six position and velocity channels.
  const std::size_t stored_channels = k > 0 ? (data.size() / (8 * k) - 1) / 4 : 0;
  if ((stored_channels != engine::kChannelCount && stored_channels != engine::kAttitudeChannel) ||
      data.size() != 8 * k * (1 + 4 * stored_channels)) {
    return absl::DataLossError("stored series has the wrong size");
  }
  const auto value = [&](std::size_t index) { return GetDouble(data.data() + 8 * index); };
  std::vector<ResidualPoint> chunk;
  chunk_points = std::max<std::size_t>(chunk_points, 1);
  chunk.reserve(std::min<std::size_t>(chunk_points, k * stored_channels));
  for (std::size_t c = 0; c < stored_channels; ++c) {
    const std::string name(engine::kChannelNames[c]);
    if (!wanted.empty() && !wanted.contains(name)) continue;
    const std::size_t base = k + 4 * k * c;
    for (std::size_t e = 0; e < k; ++e) {
      if (!(value(base + 3 * k + e) > 0.0)) continue;  // not observed at this epoch (σ = 0)
      chunk.push_back(ResidualPoint{name, value(e), value(base + e), value(base + k + e), value(base + 2 * k + e),
                                    3.0 * value(base + 3 * k + e)});
      if (chunk.size() >= chunk_points) {
        if (!consume(chunk)) return absl::OkStatus();
        chunk.clear();
      }
    }
  }
  if (!chunk.empty()) consume(chunk);
  return absl::OkStatus();
}

}  // namespace insdiag::kb

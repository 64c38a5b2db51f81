// insdiag fleet QUERY [options] [--json] [--server ADDR] — fleet statistics (docs/FLEET.md):
//   stats    [--unit-type T] [--confidence C]           counts; failures, MTBF with χ² bounds per module role
//   counts   [--unit-type T] [--period month|quarter|year] [--mode M] [--batch B]
//                                                       confirmed failures by mode × unit type × batch × period
//   pareto   [--unit-type T]                            failure modes by confirmed failures, cumulative share
//   weibull  --role R [--mode M] [--unit-type T] [--confidence C]
//                                                       Weibull life with censoring, B10
//   trend    --parameter P [--unit-type T] [--batch B]  per batch and month: median, quartiles; slope per year
//   trends   --parameter P [--unit-type T] [--unit U] [--page-size N] [--page-token T]
//                                                       the parameter's identified values over time
//   rank     [--unit-type T] [--page-size N] [--page-token T]
//                                                       units by fault probability of their latest diagnosis
// --unit-type defaults to INS-2000 where one is required (trend, trends).
#include <ostream>

#include "insdiag/client/unary.h"
#include "insdiag/v1/fleet.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class FleetVerb final : public Verb {
 public:
  std::string Name() const override { return "fleet"; }
  std::string Summary() const override {
    return "Fleet statistics: stats | counts | pareto | weibull | trend | trends | rank";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("QUERY", &query_, "stats | counts | pareto | weibull | trend | trends | rank");
    options.Option("--unit-type", &unit_type_, "Only this unit type (unitTypes/{t} or its name)");
    options.Option("--role", &role_, "weibull: the module role, e.g. gyro.x");
    options.Option("--mode", &mode_, "counts, weibull: only this failure mode (failureModes/{id} or the id)");
    options.Option("--parameter", &parameter_, "trend, trends: an identified parameter, e.g. gyro_bias_gm.x.sigma");
    options.Option("--batch", &batch_, "counts, trend: only this production batch, e.g. 2023Q2");
    options.Option("--period", &period_, "counts: month (default), quarter or year");
    options.Option("--unit", &unit_, "trends: only this unit (units/{serial} or the serial)");
    options.Option("--confidence", &confidence_, "stats, weibull: of the bounds (default 0.90)");
    options.Option("--page-size", &page_size_, "trends, rank: entries per page (default 50, at most 1000)");
    options.Option("--page-token", &page_token_, "trends, rank: the next page");
    options.Flag("--json", &json_, "Print the response as JSON (insdiag.v1 fleet messages)");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    if (auto s = ParseDouble(confidence_, "--confidence", &confidence_value_); !s.ok()) {
      return UsageError(err, Name(), std::string(s.message()));
    }
    if (auto s = ParseInt(page_size_, "--page-size", &page_size_value_); !s.ok()) {
      return UsageError(err, Name(), std::string(s.message()));
    }
    stub_ = v1::FleetService::NewStub(server_.Connect());
    if (query_ == "stats") return Stats(out, err);
    if (query_ == "counts") return Counts(out, err);
    if (query_ == "pareto") return Pareto(out, err);
    if (query_ == "weibull") return Weibull(out, err);
    if (query_ == "trend") return Trend(out, err);
    if (query_ == "trends") return Trends(out, err);
    if (query_ == "rank") return Rank(out, err);
    return UsageError(err, Name(), "QUERY: '" + query_ + "' is not stats, counts, pareto, weibull, trend, trends or rank");
  }

 private:
  std::string UnitType(bool required) const {
    return ResourceName("unitTypes", unit_type_.empty() && required ? "INS-2000" : unit_type_);
  }

  template <typename Response, typename Call>
  int Answer(const std::string& what, Call&& call, std::ostream& out, std::ostream& err,
             void (*print)(const Response&, std::ostream&)) {
    auto response = client::CallUnary<Response>(std::forward<Call>(call));
    if (!response.ok()) return RequestFailed(err, Name(), what, response.status());
    if (json_) return PrintJson(*response, out, err);
    print(*response, out);
    return kExitOk;
  }

  int Stats(std::ostream& out, std::ostream& err) {
    v1::GetFleetStatisticsRequest request;
    request.set_unit_type(UnitType(false));
    request.set_confidence(confidence_value_);
    return Answer<v1::FleetStatistics>(
        "fleet statistics",
        [&](grpc::ClientContext* c, v1::FleetStatistics* r) { return stub_->GetFleetStatistics(c, request, r); }, out,
        err, +[](const v1::FleetStatistics& s, std::ostream& o) {
          o << (s.unit_type().empty() ? "whole fleet" : s.unit_type()) << ": " << s.unit_count() << " units, "
            << s.run_count() << " runs, " << s.analysis_count() << " analyses (counted " << DateTime(s.counts_time())
            << "); " << s.failure_count() << " confirmed failures, " << s.no_fault_found_count()
            << " no fault found\n";
          Table table({"role", "parts", "failures", "NFF", "hours", "per 10^6 h", "MTBF [h]",
                       Percent(s.confidence()) + " lower", "upper"});
          for (const auto& r : s.failure_rates()) {
            table.Add({r.module_role(), std::to_string(r.modules()), std::to_string(r.failures()),
                       std::to_string(r.no_fault_found()), Number(r.operating_hours(), 6),
                       Number(r.failures_per_million_hours(), 3), r.failures() > 0 ? Number(r.mtbf_hours(), 4) : "-",
                       Number(r.mtbf_lower_hours(), 4), r.mtbf_upper_hours() > 0 ? Number(r.mtbf_upper_hours(), 4) : "∞"});
          }
          table.Print(o);
        });
  }

  int Counts(std::ostream& out, std::ostream& err) {
    v1::ListFailureCountsRequest request;
    request.set_unit_type(UnitType(false));
    request.set_period(period_);
    request.set_failure_mode(ResourceName("failureModes", mode_));
    request.set_batch(batch_);
    return Answer<v1::ListFailureCountsResponse>(
        "failure counts",
        [&](grpc::ClientContext* c, v1::ListFailureCountsResponse* r) { return stub_->ListFailureCounts(c, request, r); },
        out, err, +[](const v1::ListFailureCountsResponse& s, std::ostream& o) {
          Table table({"period", "failure mode", "role", "unit type", "batch", "failures"});
          for (const auto& c : s.counts()) {
            table.Add({Date(c.period_start()), c.failure_mode(), c.module_role(), c.unit_type(), c.batch(),
                       std::to_string(c.failures())});
          }
          table.Print(o);
          o << "total " << s.total() << "\n";
        });
  }

  int Pareto(std::ostream& out, std::ostream& err) {
    v1::GetFailureParetoRequest request;
    request.set_unit_type(UnitType(false));
    return Answer<v1::FailurePareto>(
        "Pareto", [&](grpc::ClientContext* c, v1::FailurePareto* r) { return stub_->GetFailurePareto(c, request, r); },
        out, err, +[](const v1::FailurePareto& s, std::ostream& o) {
          Table table({"failure mode", "role", "failures", "share", "cumulative"});
          for (const auto& e : s.entries()) {
            table.Add({e.failure_mode(), e.module_role(), std::to_string(e.failures()), Percent(e.share()),
                       Percent(e.cumulative_share())});
          }
          table.Print(o);
          o << "total " << s.total_failures() << " confirmed failures\n";
        });
  }

  int Weibull(std::ostream& out, std::ostream& err) {
    if (role_.empty()) return UsageError(err, Name(), "weibull: --role is required, e.g. --role gyro.x");
    v1::GetWeibullFitRequest request;
    request.set_unit_type(UnitType(false));
    request.set_module_role(role_);
    request.set_failure_mode(ResourceName("failureModes", mode_));
    request.set_confidence(confidence_value_);
    return Answer<v1::WeibullFit>(
        "Weibull fit", [&](grpc::ClientContext* c, v1::WeibullFit* r) { return stub_->GetWeibullFit(c, request, r); },
        out, err, +[](const v1::WeibullFit& w, std::ostream& o) {
          o << w.module_role() << (w.failure_mode().empty() ? "" : ", " + w.failure_mode()) << ": " << w.failures()
            << " failures, " << w.suspensions() << " suspensions\n";
          Table table({"", "estimate", Percent(w.confidence()) + " lower", "upper"});
          table.Add({"shape β", Number(w.shape()), Number(w.shape_lower()), Number(w.shape_upper())});
          table.Add({"scale η [h]", Number(w.scale_hours(), 6), Number(w.scale_lower_hours(), 6),
                     Number(w.scale_upper_hours(), 6)});
          table.Add({"B10 life [h]", Number(w.b10_hours(), 6), Number(w.b10_lower_hours(), 6),
                     Number(w.b10_upper_hours(), 6)});
          table.Print(o);
        });
  }

  int Trend(std::ostream& out, std::ostream& err) {
    if (parameter_.empty()) return UsageError(err, Name(), "trend: --parameter is required, e.g. gyro_bias_gm.x.sigma");
    v1::GetParameterTrendRequest request;
    request.set_unit_type(UnitType(true));
    request.set_parameter(parameter_);
    request.set_batch(batch_);
    return Answer<v1::ParameterTrend>(
        "parameter trend", [&](grpc::ClientContext* c, v1::ParameterTrend* r) { return stub_->GetParameterTrend(c, request, r); },
        out, err, +[](const v1::ParameterTrend& t, std::ostream& o) {
          o << t.parameter() << " of " << t.unit_type() << ": nominal " << Number(t.nominal()) << " " << t.unit()
            << ", tolerance " << Number(t.tolerance()) << "; slope " << Number(t.slope_per_year(), 3) << " "
            << t.unit() << " per year (" << Percent(t.relative_slope_per_year()) << " of nominal)\n";
          Table table({"batch", "month", "analyses", "median", "p25", "p75", "mean"});
          for (const auto& b : t.buckets()) {
            table.Add({b.batch(), Date(b.month()).substr(0, 7), std::to_string(b.count()), Number(b.median()),
                       Number(b.p25()), Number(b.p75()), Number(b.mean())});
          }
          table.Print(o);
        });
  }

  int Trends(std::ostream& out, std::ostream& err) {
    if (parameter_.empty()) return UsageError(err, Name(), "trends: --parameter is required, e.g. gyro_bias_gm.x.sigma");
    v1::ListParameterTrendsRequest request;
    request.set_unit_type(UnitType(true));
    request.set_parameter(parameter_);
    request.set_unit(ResourceName("units", unit_));
    request.set_page_size(page_size_value_);
    request.set_page_token(page_token_);
    return Answer<v1::ListParameterTrendsResponse>(
        "parameter values",
        [&](grpc::ClientContext* c, v1::ListParameterTrendsResponse* r) { return stub_->ListParameterTrends(c, request, r); },
        out, err, +[](const v1::ListParameterTrendsResponse& s, std::ostream& o) {
          Table table({"time", "unit", "hours", "value", "± std error", "analysis"});
          for (const auto& p : s.points()) {
            table.Add({DateTime(p.time()), p.unit(), Number(p.operating_hours(), 6), Number(p.value()),
                       Number(p.std_error(), 2), p.analysis()});
          }
          table.Print(o);
          if (!s.next_page_token().empty()) o << "next page: --page-token " << s.next_page_token() << "\n";
        });
  }

  int Rank(std::ostream& out, std::ostream& err) {
    v1::RankUnitsRequest request;
    request.set_unit_type(UnitType(false));
    request.set_page_size(page_size_value_);
    request.set_page_token(page_token_);
    return Answer<v1::RankUnitsResponse>(
        "unit ranking", [&](grpc::ClientContext* c, v1::RankUnitsResponse* r) { return stub_->RankUnits(c, request, r); },
        out, err, +[](const v1::RankUnitsResponse& s, std::ostream& o) {
          Table table({"unit", "batch", "hours", "P(fault)", "top module", "failure mode", "p", "diagnosis"});
          for (const auto& u : s.units()) {
            table.Add({u.unit(), u.batch(), Number(u.operating_hours(), 6), Number(u.fault_probability(), 3),
                       u.top_module(), u.top_failure_mode(), Number(u.top_probability(), 3), u.diagnosis()});
          }
          table.Print(o);
          if (!s.next_page_token().empty()) o << "next page: --page-token " << s.next_page_token() << "\n";
        });
  }

  std::string query_, unit_type_, role_, mode_, parameter_, batch_, period_, unit_, confidence_, page_size_, page_token_;
  double confidence_value_ = 0;
  int page_size_value_ = 0;
  bool json_ = false;
  ServerFlags server_;
  std::unique_ptr<v1::FleetService::Stub> stub_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_fleet() { return std::make_unique<FleetVerb>(); }

}  // namespace insdiag::cli

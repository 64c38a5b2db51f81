#include "insdiag/engine/ident/allan.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>

#include "insdiag/benchrun/bench_run_csv.h"
#include "scenarios.h"

namespace insdiag::engine::ident {
namespace {

using testing::kDeg;
using testing::kDegPerHour;
using testing::kMicroG;

sim::TableProfile StaticProfile(double seconds) {
  sim::TableProfile p;
  p.name = "static";
  p.angular_acceleration_rad_s2 = 10.0 * kDeg;
  p.thermal.ambient_degc = 25.0;
  p.segments = {{sim::TableSegment::Kind::kHold, seconds, 0, 0, 0}};
  return p;
}

void Print(const AllanResult& r) {
  for (const AllanChannel& ch : r.channels) {
    std::printf("%s: structure %s, chi2 %.3g dof %d p %.3g delta %.3g\n", ch.name.c_str(),
                ch.fit.markov_structure ? "markov" : "flicker", ch.fit.generalized_chi2, ch.fit.dof, ch.fit.p_value,
                ch.fit.discrepancy);
    for (int k = 0; k < kAllanParameterCount; ++k) {
      const auto& t = ch.fit.parameters[static_cast<size_t>(k)];
      if (t.included) std::printf("   %-13s %.6g ± %.3g (z %.3g)\n", AllanParameterName(static_cast<AllanParameter>(k)), t.value, t.std_error, t.z);
    }
    for (const auto& u : ch.fit.unresolved) std::printf("   dropped %s\n", u.c_str());
    for (const auto& u : ch.fit.notes) std::printf("   note %s\n", u.c_str());
  }
}

TEST(AllanExplore, TwoHourStatic) {
  auto t0 = std::chrono::steady_clock::now();
  const auto sim = testing::SimulateOrDie(testing::NavigationGradeUnit(), StaticProfile(7200.0), 100.0, 7);
  auto t1 = std::chrono::steady_clock::now();
  auto r = AllanAnalysis(sim.run, AllanOptions{});
  auto t2 = std::chrono::steady_clock::now();
  ASSERT_TRUE(r.ok()) << r.status();
  std::printf("sim %.2f s, allan %.3f s, segments %zu, points %zu\n", std::chrono::duration<double>(t1 - t0).count(),
              std::chrono::duration<double>(t2 - t1).count(), r->segments.size(), r->channels[0].curve.size());
  Print(*r);
  const auto& c = r->channels[0].curve;
  for (const auto& p : c) std::printf("  tau %8.2f adev %.4g [%.4g %.4g] edf %.4g fit %.4g res %.3g noise %d\n", p.tau_s, p.adev, p.ci_low, p.ci_high, p.edf, p.fitted_adev, p.log_residual, static_cast<int>(p.noise));
}

TEST(AllanExplore, Real) {
  auto t0 = std::chrono::steady_clock::now();
  auto run = benchrun::ReadBenchRunFile(std::string(INSDIAG_SHARED_DIR) + "/data/real/rlg-static-psins.csv");
  ASSERT_TRUE(run.ok()) << run.status();
  auto t1 = std::chrono::steady_clock::now();
  auto r = AllanAnalysis(*run, AllanOptions{});
  auto t2 = std::chrono::steady_clock::now();
  ASSERT_TRUE(r.ok()) << r.status();
  std::printf("read %.2f s, allan %.3f s, segments %zu, points %zu\n", std::chrono::duration<double>(t1 - t0).count(),
              std::chrono::duration<double>(t2 - t1).count(), r->segments.size(), r->channels[0].curve.size());
  Print(*r);
  for (int c : {0, 2, 3}) {
  const auto& cv = r->channels[c].curve;
  for (const auto& p : cv) std::printf("  tau %8.2f adev %.4g [%.4g %.4g] edf %.4g fit %.4g res %.3g noise %d\n", p.tau_s, p.adev, p.ci_low, p.ci_high, p.edf, p.fitted_adev, p.log_residual, static_cast<int>(p.noise));
  }
}

}  // namespace
}  // namespace insdiag::engine::ident

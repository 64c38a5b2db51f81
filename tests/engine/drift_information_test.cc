// The observed information of the drift likelihood from the smoother's
// moments (Oakes' identity; ident/drift_em.h, MomentInformation) against the
// second differences of ℓ, at the likelihood's maximum, for every kind of
// parameter the identification's errors come from: a drift's σ and τ, a
// bias random walk's density with its drift's σ, a second-order pair's σ₂,
// α and β with its drift's σ.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <string>
#include <vector>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/ident/drift_likelihood.h"
#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_field.h"
#include "scenarios.h"

namespace insdiag::engine::ident {
namespace {

using testing::kDegPerHour;

// The identification's unit of the drift coverage tests: τ = 300 s, twenty
// correlation times in the two-hour `full` profile.
sim::SimulatedUnit ShortTauUnit() {
  sim::SimulatedUnit u = testing::NavigationGradeUnit();
  for (auto& b : u.gyro.bias) b = {0.05 * kDegPerHour, 300.0};
  for (auto& b : u.acc.bias) b.tau_s = 300.0;
  return u;
}

sim::TrueEffect Hidden(const std::string& selector) {
  sim::TrueEffect e;
  auto terms = ParseEffectSelector(selector);
  EXPECT_TRUE(terms.ok()) << terms.status();
  if (terms.ok()) e.term = terms->front();
  return e;
}

struct Measured {
  DriftInformation information;
  double wall_s = 0.0, cpu_s = 0.0;
};

Measured InformationBy(const EpochRun& run, const ErrorModel& model, const std::vector<std::string>& names,
                       DriftLikelihoodOptions::Information method, double curvature_step) {
  DriftLikelihoodOptions options;
  options.information = method;
  options.curvature_step = curvature_step;
  const auto wall = std::chrono::steady_clock::now();
  const std::clock_t cpu = std::clock();
  auto information = ObservedDriftInformation(run, model, names, options);
  Measured out;
  out.cpu_s = static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC;
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count();
  EXPECT_TRUE(information.ok()) << information.status();
  if (information.ok()) out.information = *std::move(information);
  return out;
}

// The standard errors in ln of each block of `sizes` consecutive
// parameters, each block's information inverted on its own (as the
// identification reports them).
std::vector<double> BlockErrors(const Eigen::MatrixXd& information, const std::vector<Eigen::Index>& sizes) {
  std::vector<double> out;
  Eigen::Index first = 0;
  for (Eigen::Index r : sizes) {
    const Eigen::MatrixXd covariance = information.block(first, first, r, r).inverse();
    for (Eigen::Index k = 0; k < r; ++k) out.push_back(std::sqrt(covariance(k, k)));
    first += r;
  }
  return out;
}

// The second differences block by block, as the identification takes them
// (r(r + 1) passes a block): the blocks' information on the diagonal.
Measured SecondDifferencesByBlock(const EpochRun& run, const ErrorModel& model, const std::vector<std::string>& names,
                                  const std::vector<Eigen::Index>& sizes, double step) {
  Measured out;
  const auto r = static_cast<Eigen::Index>(names.size());
  out.information.information = Eigen::MatrixXd::Zero(r, r);
  Eigen::Index first = 0;
  for (Eigen::Index size : sizes) {
    const std::vector<std::string> block(names.begin() + first, names.begin() + first + size);
    const Measured m = InformationBy(run, model, block, DriftLikelihoodOptions::Information::kSecondDifferences, step);
    if (m.information.information.rows() != size) return out;
    out.information.information.block(first, first, size, size) = m.information.information;
    out.information.filter_passes += m.information.filter_passes;
    out.wall_s += m.wall_s;
    out.cpu_s += m.cpu_s;
    first += size;
  }
  return out;
}

// The second differences' step: the identification's 0.15 in ln is a
// chord, not a tangent, where ℓ is not quadratic over ±0.15 (the pair
// below: α's SE 1.03 at 0.15, 1.16 at 0.02, 1.18 from the moments; β's
// 0.040, 0.043, 0.044). At 0.02 the second differences are local, and what
// is compared.
constexpr double kLocalStep = 0.02;

// Compares the two at `model` (the likelihood's maximum in `names`): the
// moments' information is symmetric and positive definite, and each
// parameter's SE from it is within `tolerance` of the local second
// differences'; the identification's own step's SEs are printed beside.
void ExpectAgreement(const EpochRun& run, const ErrorModel& model, const std::vector<std::string>& names,
                     const std::vector<Eigen::Index>& blocks, double tolerance) {
  using Method = DriftLikelihoodOptions::Information;
  const Measured coarse = SecondDifferencesByBlock(run, model, names, blocks, 0.15);
  const Measured local = SecondDifferencesByBlock(run, model, names, blocks, kLocalStep);
  const Measured moments = InformationBy(run, model, names, Method::kSmootherMoments, 0.15);
  const Eigen::MatrixXd& m = moments.information.information;
  const auto r = static_cast<Eigen::Index>(names.size());
  ASSERT_EQ(m.rows(), r);
  ASSERT_EQ(local.information.information.rows(), r);
  ASSERT_EQ(coarse.information.information.rows(), r);
  EXPECT_LE((m - m.transpose()).cwiseAbs().maxCoeff(), 1e-9 * m.cwiseAbs().maxCoeff());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(m);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0) << "not positive definite:\n" << m;
  const std::vector<double> se_c = BlockErrors(coarse.information.information, blocks);
  const std::vector<double> se_l = BlockErrors(local.information.information, blocks);
  const std::vector<double> se_m = BlockErrors(m, blocks);
  for (size_t k = 0; k < names.size(); ++k) {
    const double relative = se_m[k] / se_l[k] - 1.0;
    std::printf("%-34s SE(ln) second differences h=0.15 %.4f, h=%.2f %.4f; moments %.4f (%+.1f %%, %+.1f %%)\n",
                names[k].c_str(), se_c[k], kLocalStep, se_l[k], se_m[k], 100.0 * (se_m[k] / se_c[k] - 1.0),
                100.0 * relative);
    EXPECT_LE(std::abs(relative), tolerance) << names[k];
  }
  std::printf("information of %td parameters: second differences %d forward passes, %.2f s wall, %.2f s CPU; "
              "moments %d forward and smoother passes, %.2f s wall, %.2f s CPU\n",
              r, coarse.information.filter_passes, coarse.wall_s, coarse.cpu_s, moments.information.filter_passes,
              moments.wall_s, moments.cpu_s);
}

// What the moments leave out: the complete-data likelihood is each drift
// state's own, without the drift noise's share of the attitude's and the
// velocity's process noise within an epoch (the score's 3 % on the branch
// not adopted); measured 0.1 % at most on the SEs of σ and τ and 1.8 % on
// a pair's.
constexpr double kRelativeTolerance = 0.03;
// A walk beside its drift's σ: ℓ is a ridge along which the two trade (the
// information's correlation 0.99), its smallest eigenvalue 0.1 % of the
// largest, so elements within 1 % of each other give SEs 12 % apart.
constexpr double kRidgeTolerance = 0.20;

// Every drift's σ and τ at their joint maximum.
TEST(DriftInformationTest, SmootherMomentsAgreeWithSecondDifferencesForDriftSigmaAndTau) {
  const sim::SimulatedUnit unit = ShortTauUnit();
  const ErrorModel truth = testing::TrueBaseModel(unit);
  const sim::SimulatedRun s = testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie("full"), 10.0, 41);
  const auto epochs = CondenseRun(s.run, truth, FilterOptions{}.update_interval_s);
  ASSERT_TRUE(epochs.ok()) << epochs.status();
  auto fit = IdentifyDriftsByLikelihood(*epochs, truth, truth, DriftSelection::Every(), DriftSelection::Every(), {});
  ASSERT_TRUE(fit.ok()) << fit.status();
  std::vector<std::string> names;
  std::vector<Eigen::Index> blocks;
  for (const DriftAxis d : DriftAxis::All()) {
    const bool identified = std::any_of(fit->identified.begin(), fit->identified.end(),
                                        [&](const ParameterEstimate& e) { return e.name == DriftTauName(d); });
    if (!identified) continue;
    names.push_back(DriftSigmaName(d));
    names.push_back(DriftTauName(d));
    blocks.push_back(2);
  }
  ASSERT_GE(names.size(), 8u) << "too few drifts identified with their τ";
  ExpectAgreement(*epochs, fit->model, names, blocks, kRelativeTolerance);
}

// A walk (acc x, K = 5σ/√τ) and a second-order pair (gyro y, σ₂ three
// drift σ, decay 900 s, period 600 s) hidden in one run, each fitted with
// its drift's σ.
TEST(DriftInformationTest, SmootherMomentsAgreeWithSecondDifferencesForWalksAndPairs) {
  constexpr DriftAxis kAccX{Sensor::kAccelerometer, 0}, kGyroY{Sensor::kGyro, 1};
  sim::SimulatedUnit unit = testing::NavigationGradeUnit();
  const ErrorModel model = testing::TrueBaseModel(unit);
  sim::TrueEffect walk = Hidden(WalkName(kAccX));
  walk.random_walk_density = 5.0 * DriftOf(model, kAccX).sigma / std::sqrt(DriftOf(model, kAccX).tau_s);
  sim::TrueEffect pair = Hidden(SecondOrderName(kGyroY));
  pair.second_order_sigma = 3.0 * DriftOf(model, kGyroY).sigma;
  pair.second_order_alpha_per_s = 1.0 / 900.0;
  pair.second_order_beta_rad_s = 2.0 * std::numbers::pi / 600.0;
  unit.effects.push_back(walk);
  unit.effects.push_back(pair);
  const sim::SimulatedRun s = testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie("full"), 10.0, 7);
  const auto epochs = CondenseRun(s.run, model, FilterOptions{}.update_interval_s);
  ASSERT_TRUE(epochs.ok()) << epochs.status();

  DriftSelection x;
  x.Set(kAccX);
  auto walks = IdentifyWalksByLikelihood(*epochs, model, model, x, 0.01, {});
  ASSERT_TRUE(walks.ok()) << walks.status();
  ASSERT_EQ(walks->structures.size(), 1u) << "the walk was not kept";
  ExpectAgreement(*epochs, walks->model,
                  {DriftSigmaName(kAccX), ParameterName(WalkName(kAccX), ParameterField::kDensity)}, {2},
                  kRidgeTolerance);

  DriftSelection y;
  y.Set(kGyroY);
  auto pairs = IdentifySecondOrdersByLikelihood(*epochs, model, model, y, 0.01, {});
  ASSERT_TRUE(pairs.ok()) << pairs.status();
  ASSERT_EQ(pairs->structures.size(), 1u) << "the pair was not kept";
  // The pair's own block: on this run the drift σ beside it runs to its
  // boundary (ℓ flat in it), where the identification too reports the
  // pair's errors from its own block (StructureCovariance).
  const std::string name = SecondOrderName(kGyroY);
  ExpectAgreement(*epochs, pairs->model,
                  {ParameterName(name, ParameterField::kSigma), ParameterName(name, ParameterField::kDecayRate),
                   ParameterName(name, ParameterField::kFrequency)},
                  {3}, kRelativeTolerance);
}

}  // namespace
}  // namespace insdiag::engine::ident

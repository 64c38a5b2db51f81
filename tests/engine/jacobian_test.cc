// The linearised model against numeric differentiation: each effect's
// regressor against its physical error function, and the filter's interval
// transition against finite differences of the nonlinear mechanisation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>

#include "insdiag/engine/filter/model_transitions.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/error_dynamics.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/table_motion.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/numerics/matrix_exponential.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

using testing::kDeg;

RegressorInputs SomeInputs() {
  RegressorInputs in;
  in.gyro_rad_s = {0.012, -0.17, 0.05};
  in.acc_mps2 = {1.3, -2.1, -9.4};
  in.temperature_delta_degc = 6.5;
  in.yaw_rad = 0.7;
  return in;
}

TEST(EffectJacobian, EveryConstantTermMatchesNumericDifferentiation) {
  const RegressorInputs in = SomeInputs();
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind != EffectKind::kConstant) continue;
    double analytic[2];
    EvaluateRegressor(term, in, analytic);
    for (int p = 0; p < term.family->parameters_per_term; ++p) {
      // Central difference around a non-zero operating point, step small against it.
      std::array<double, 2> base = {1e-4, -2e-4};
      const double h = 1e-7;
      auto plus = base, minus = base;
      plus[static_cast<size_t>(p)] += h;
      minus[static_cast<size_t>(p)] -= h;
      const Eigen::Vector3d numeric =
          (ConstantEffectError(term, in, plus) - ConstantEffectError(term, in, minus)) / (2.0 * h);
      for (int axis = 0; axis < 3; ++axis) {
        const double expected = axis == term.axis ? analytic[p] : 0.0;
        EXPECT_NEAR(numeric[axis], expected, 1e-6 * std::max(1.0, std::abs(expected)))
            << term.ParameterName(p) << " axis " << axis;
      }
    }
  }
}

TEST(EffectJacobian, ParsesEveryTermNameBack) {
  for (const EffectTerm& term : AllCatalogueTerms()) {
    auto parsed = ParseEffectSelector(term.Name());
    ASSERT_TRUE(parsed.ok()) << parsed.status();
    ASSERT_EQ(parsed->size(), 1u);
    EXPECT_EQ(parsed->front(), term);
  }
  EXPECT_FALSE(ParseEffectSelector("gyro_scale_factor.q").ok());
  EXPECT_FALSE(ParseEffectSelector("gyro_misalignment.xx").ok());
  EXPECT_EQ(ParseEffectSelector("gyro_g_sensitivity")->size(), 9u);
}

TEST(EffectJacobian, FaultsTakeTheirOnsetAndOthersRefuseOne) {
  auto step = ParseEffectSelector("gyro_bias_step.x@1500.5");
  ASSERT_TRUE(step.ok()) << step.status();
  EXPECT_EQ(step->front().Name(), "gyro_bias_step.x");
  EXPECT_EQ(ParseOnset("gyro_bias_step.x@1500.5")->value_or(-1.0), 1500.5);
  EXPECT_FALSE(ParseOnset("acc_bias_ramp.z")->has_value());
  EXPECT_FALSE(ParseEffectSelector("gyro_scale_factor.x@10").ok());
  EXPECT_FALSE(ParseEffectSelector("gyro_bias_step.x@soon").ok());
  // A model's name of a fault carries its onset, and parses back to the term and the onset.
  ErrorModel model;
  model.effects.push_back({.term = step->front(), .onset_s = 1500.5});
  const std::string name = model.EffectNames().front();
  EXPECT_EQ(name, "gyro_bias_step.x@1500.5");
  EXPECT_EQ(ParseEffectSelector(name)->front(), step->front());
  EXPECT_EQ(ParseOnset(name)->value_or(-1.0), 1500.5);
  EXPECT_EQ(model.ParameterCount(), ErrorModel{}.ParameterCount() + 2);  // magnitude and onset
}

Eigen::MatrixXd MatrixPower(const Eigen::MatrixXd& m, int k) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Identity(m.rows(), m.cols());
  for (int i = 0; i < k; ++i) out = out * m;
  return out;
}

// Error-state coordinates of `perturbed` relative to `nominal` (the filter's
// definitions: phi-angle, NED velocity, NED metres).
Eigen::Matrix<double, 9, 1> ErrorBetween(const nav::NavState& perturbed, const nav::NavState& nominal,
                                         const Site& site) {
  Eigen::Matrix<double, 9, 1> e;
  // C̃ = (I − [ψ×]) C  ⇒  [ψ×] ≈ I − C̃ Cᵀ.
  const Eigen::Matrix3d E = perturbed.q_b_n.toRotationMatrix() * nominal.q_b_n.toRotationMatrix().transpose();
  e.segment<3>(0) = -0.5 * Eigen::Vector3d(E(2, 1) - E(1, 2), E(0, 2) - E(2, 0), E(1, 0) - E(0, 1));
  e.segment<3>(3) = perturbed.v_n_mps - nominal.v_n_mps;
  const Eigen::Matrix3d C_ref = nominal.q_b_n.toRotationMatrix();
  const auto zp = Observe(perturbed, site, C_ref);
  const auto zn = Observe(nominal, site, C_ref);
  e.segment<3>(6) = Eigen::Vector3d(zp[0] - zn[0], zp[1] - zn[1], -(zp[2] - zn[2]));
  return e;
}

class TransitionJacobian : public ::testing::Test {
 protected:
  void SetUp() override {
    // One second of a turning, tilted table with perfect sensors.
    sim::TableProfile profile;
    profile.angular_acceleration_rad_s2 = 10.0 * kDeg;
    profile.initial_inner_rad = 30.0 * kDeg;
    profile.mount_rpy_rad = {0.0, 0.0, 45.0 * kDeg};
    using K = sim::TableSegment::Kind;
    profile.segments = {{K::kRotateOuter, 5.0, 10.0 * kDeg, 0, 0}};
    sim::SimulationOptions o;
    o.sample_rate_hz = 100.0;
    o.site = testing::TestSite();
    o.perfect_sensors = true;
    run_ = sim::Simulate(sim::SimulatedUnit{}, profile, o)->run;
    site_ = o.site;
    model_.gyro.white_noise_density.setConstant(1e-6);
    model_.acc.white_noise_density.setConstant(1e-5);
    for (auto& b : model_.gyro.bias) b = {1e-7, 1000.0};
    for (auto& b : model_.acc.bias) b = {1e-4, 1000.0};
  }

  nav::NavState StartState() const {
    nav::NavState s;
    s.q_b_n = Eigen::Quaterniond(nav::EulerToDcm(run_.samples[first_].ref_rpy_rad));
    s.latitude_rad = site_.latitude_rad;
    s.longitude_rad = site_.longitude_rad;
    s.height_m = site_.height_m;
    return s;
  }

  // Mechanises samples first_+1 … first_+count with sensor errors added by `error(k, gyro, acc)`.
  template <typename ErrorFn>
  nav::NavState Mechanise(nav::NavState s, int count, ErrorFn error) const {
    const double dt = 0.01;
    nav::ReferenceMotion motion(run_);
    for (int j = 1; j <= count; ++j) {
      const ImuSample& smp = run_.samples[first_ + static_cast<size_t>(j)];
      Eigen::Vector3d g = smp.gyro_rad_s, a = smp.acc_mps2;
      error(smp, g, a);
      const nav::ImuIncrement cur{g * dt, a * dt};
      s = nav::PropagateStrapdown(s, cur, motion.Compensation(first_ + static_cast<size_t>(j)), dt);
    }
    return s;
  }

  // The filter's interval transition over the same samples: the run from
  // sample first_ condensed into one interval, as RunForwardFilter builds it.
  IntervalTransition Transition(const ErrorModel& model, int count) const {
    BenchRun part = run_;
    part.samples.assign(run_.samples.begin() + static_cast<std::ptrdiff_t>(first_),
                        run_.samples.begin() + static_cast<std::ptrdiff_t>(first_) + count + 1);
    const auto epochs = CondenseRun(part, model, count * 0.01);
    EXPECT_TRUE(epochs.ok()) << epochs.status();
    const StateLayout layout(model);
    ModelTransitions transitions(model, layout, *epochs);
    return transitions.Build(epochs->epochs.front());
  }

  BenchRun run_;
  Site site_;
  ErrorModel model_;
  size_t first_ = 100;
};

TEST_F(TransitionJacobian, NavigationBlockMatchesTheMechanisation) {
  const int count = 100;  // one second
  const IntervalTransition t = Transition(model_, count);
  const nav::NavState nominal = Mechanise(StartState(), count, [](const ImuSample&, auto&, auto&) {});
  // Perturb each navigation error coordinate and compare the propagated difference.
  const double steps[9] = {1e-5, 1e-5, 1e-5, 1e-3, 1e-3, 1e-3, 1.0, 1.0, 1.0};
  for (int i = 0; i < 9; ++i) {
    nav::NavState start = StartState();
    Eigen::Matrix<double, 9, 1> dx = Eigen::Matrix<double, 9, 1>::Zero();
    dx[i] = steps[i];
    start.q_b_n = (nav::RotationVectorToQuaternion(-dx.segment<3>(0)) * start.q_b_n).normalized();
    start.v_n_mps += dx.segment<3>(3);
    const double rm = wgs84::MeridianRadiusM(site_.latitude_rad) + site_.height_m;
    const double rn = wgs84::PrimeVerticalRadiusM(site_.latitude_rad) + site_.height_m;
    start.latitude_rad += dx[6] / rm;
    start.longitude_rad += dx[7] / (rn * std::cos(site_.latitude_rad));
    start.height_m -= dx[8];
    const nav::NavState end = Mechanise(start, count, [](const ImuSample&, auto&, auto&) {});
    const Eigen::Matrix<double, 9, 1> numeric = ErrorBetween(end, nominal, site_);
    const Eigen::Matrix<double, 9, 1> linear = t.A * dx;
    for (int r = 0; r < 9; ++r) {
      EXPECT_NEAR(numeric[r], linear[r], 2e-3 * linear.cwiseAbs().maxCoeff() + 1e-12)
          << "perturbed " << i << ", row " << r;
    }
  }
}

// An interval of one or two samples, where the position's coupling is of
// third order in Δt: each row group (attitude, velocity, position) of every
// drift's column against the mechanisation, to 1 % of that group's largest
// entry. The mechanisation's trapezoidal position integration gives a gyro
// error g·δω·Δt³/4 of position over one sample, the continuous error
// equations Δt³/6 (error_dynamics.cc).
TEST_F(TransitionJacobian, DriftColumnsOfOneAndTwoSampleIntervalsMatchTheMechanisationRowByRow) {
  ErrorModel model;
  model.reference = model_.reference;
  for (auto* triad : {&model.gyro, &model.acc}) {
    for (auto& b : triad->bias) b = {1e-3, 1e6};
  }
  for (int count : {1, 2}) {
    const nav::NavState nominal =
        Mechanise(StartState(), count, [](const ImuSample&, auto&, auto&) {});
    const IntervalTransition t = Transition(model, count);
    for (int axis = 0; axis < kSensorAxisCount; ++axis) {
      // Large enough that one sample's position change stands above the
      // ~1e-9 m resolution of latitude, small enough to stay linear.
      const double size = 3e-2;
      const nav::NavState end = Mechanise(
          StartState(), count,
          [&](const ImuSample&, auto& g, auto& a) { (axis < 3 ? g : a)[axis % 3] += size; });
      const Eigen::Matrix<double, 9, 1> numeric = ErrorBetween(end, nominal, site_) / size;
      const Eigen::Matrix<double, 9, 1> linear = t.B.col(axis);
      // Entries far below the column's largest (the transport rate's) are not compared.
      const double floor = 1e-6 * linear.cwiseAbs().maxCoeff();
      for (int group = 0; group < 3; ++group) {
        const double scale = linear.segment<3>(3 * group).cwiseAbs().maxCoeff();
        for (int r = 3 * group; r < 3 * group + 3; ++r) {
          EXPECT_NEAR(numeric[r], linear[r], 1e-2 * scale + floor)
              << count << " sample(s), sensor axis " << axis << ", row " << r;
        }
      }
    }
  }
}

TEST_F(TransitionJacobian, EveryEffectColumnMatchesTheMechanisation) {
  const int count = 100;
  const nav::NavState nominal = Mechanise(StartState(), count, [](const ImuSample&, auto&, auto&) {});
  const double temp0 = run_.samples[0].temp_degc;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind != EffectKind::kConstant) continue;
    ErrorModel model = model_;
    ModelEffect effect;
    effect.term = term;
    effect.prior_sigma = {1.0, 1.0};
    model.effects.push_back(effect);
    const IntervalTransition t = Transition(model, count);
    const StateLayout layout(model);
    for (int p = 0; p < term.family->parameters_per_term; ++p) {
      // Large enough that the position difference stands far above the ~1e-9 m
      // resolution of latitude differences in double precision, small enough
      // to stay linear (attitude errors below 1e-4 rad).
      std::array<double, 2> value = {0.0, 0.0};
      value[static_cast<size_t>(p)] = term.family->regressor == Regressor::kTemperature ? 1e-5 : 1e-4;
      const nav::NavState end = Mechanise(StartState(), count, [&](const ImuSample& smp, auto& g, auto& a) {
        RegressorInputs in;
        in.gyro_rad_s = smp.gyro_rad_s;
        in.acc_mps2 = smp.acc_mps2;
        in.temperature_delta_degc = smp.temp_degc - temp0;
        in.yaw_rad = smp.ref_rpy_rad.z();
        const Eigen::Vector3d err = ConstantEffectError(term, in, value);
        (term.family->sensor == Sensor::kGyro ? g : a) += err;
      });
      const Eigen::Matrix<double, 9, 1> numeric = ErrorBetween(end, nominal, site_);
      const int column = layout.EffectOffset(0) + p - layout.sensor_begin();
      const Eigen::Matrix<double, 9, 1> linear = t.B.col(column) * value[static_cast<size_t>(p)];
      const double scale = linear.cwiseAbs().maxCoeff();
      for (int r = 0; r < 9; ++r) {
        EXPECT_NEAR(numeric[r], linear[r], 5e-3 * scale + 1e-14) << term.ParameterName(p) << " row " << r;
      }
    }
  }
}

// What one sample carries of a drift, a walk and a pair (their means over
// the sample) against closed forms: a Gauss–Markov drift's (Maybeck,
// Stochastic Models vol. 1 §4.9, as tests/benchsim/sensors.py writes them),
// a walk's (Cov(v, n) = K²Δt/2, Var v = K²Δt/3) and a pair's Ψ =
// (1/Δt) F⁻¹(e^{FΔt} − I).
TEST(SampleMeans, MatchTheirClosedForms) {
  struct Drift {
    double sigma, tau_s, dt_s;
  };
  for (const Drift& c :
       {Drift{1e-3, 300.0, 1.0}, Drift{1e-2, 0.05, 0.01}, Drift{4.8e-8, 1800.0, 0.005}}) {
    ErrorModel model;
    model.acc.bias[1] = {c.sigma, c.tau_s};
    const StateLayout layout(model);
    const auto means = SensorBlocks::SampleMeans(model, layout, c.dt_s);
    const SensorBlocks::SampleMean& m =
        means[static_cast<size_t>(SensorAxisIndex(Sensor::kAccelerometer, 1))];
    const double beta = 1.0 / c.tau_s, x = beta * c.dt_s, phi = std::exp(-x),
                 q2 = 2.0 * beta * c.sigma * c.sigma;
    const double one_minus_phi = -std::expm1(-x);
    const double g =
        x < 1e-3 ? x * x * x / 3.0 - x * x * x * x / 4.0 : x - one_minus_phi * (3.0 - phi) / 2.0;
    const double cross = q2 * one_minus_phi * one_minus_phi / (2.0 * beta * beta) / c.dt_s;
    const double noise = q2 / (beta * beta * beta) * g / (c.dt_s * c.dt_s);
    EXPECT_NEAR(m.transition(0, 0), one_minus_phi / x, 1e-12) << c.tau_s;
    EXPECT_NEAR(m.cross(0, 0), cross, 1e-7 * cross) << c.tau_s;
    EXPECT_NEAR(m.noise(0, 0), noise, 1e-6 * noise) << c.tau_s;
  }
  ErrorModel model;
  for (const char* selector : {"gyro_bias_rw.z", "acc_bias_second_order.x"}) {
    ModelEffect e;
    e.term = ParseEffectSelector(selector)->front();
    e.random_walk_density = 1e-4;
    e.second_order_sigma = 1e-3;
    e.second_order_alpha_per_s = 1.0 / 3.0;
    e.second_order_beta_rad_s = 2.0 * std::numbers::pi / 0.7;
    model.effects.push_back(e);
  }
  const StateLayout layout(model);
  const double dt = 0.01;
  const auto means = SensorBlocks::SampleMeans(model, layout, dt);
  const SensorBlocks blocks = SensorBlocks::Identity(layout);
  for (size_t b = 0; b < blocks.blocks.size(); ++b) {
    const int offset = blocks.blocks[b].offset + StateLayout::kNavigationSize;
    if (offset == layout.EffectOffset(0)) {
      const double c = 1e-4 * 1e-4;
      EXPECT_NEAR(means[b].transition(0, 0), 1.0, 1e-12);
      EXPECT_NEAR(means[b].cross(0, 0), c * dt / 2.0, 1e-9 * c * dt);
      EXPECT_NEAR(means[b].noise(0, 0), c * dt / 3.0, 1e-9 * c * dt);
    } else if (offset == layout.EffectOffset(1)) {
      const double alpha = 1.0 / 3.0, w = 2.0 * std::numbers::pi / 0.7;
      Eigen::Matrix2d F;
      F << -alpha, -w, w, -alpha;
      const Eigen::Matrix2d psi =
          F.inverse() * (numerics::MatrixExponential(F * dt) - Eigen::Matrix2d::Identity()) / dt;
      EXPECT_LT((means[b].transition - psi).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}

// The condensed interval's B, Q_ns and the process noise's part of Q_nn for
// drifts, walks and pairs (their coupling reconstructed as a quadratic from
// three moments, epoch_run.h) against the sums over the samples themselves,
// with each sample's coupling b_j taken from the mechanisation: one second
// of a table whose turn is ramping up, so the coupling rotates and bends.
TEST_F(TransitionJacobian, DecayingStatesMatchTheSumsOverTheirSamples) {
  const int count = 100;
  const double dt = 0.01;
  const nav::NavState nominal = Mechanise(StartState(), count, [](const ImuSample&, auto&, auto&) {});
  // b_j per sensor axis (gyro x, y, z, accelerometer x, y, z) by a small error on sample j alone.
  std::vector<Matrix96d> b(static_cast<size_t>(count) + 1, Matrix96d::Zero());
  for (int axis = 0; axis < 6; ++axis) {
    // Large enough that the position change stands far above the ~1e-9 m
    // resolution of latitude in double precision, small enough to stay linear.
    const double size = axis < 3 ? 1e-3 : 1e-1;
    for (int j = 1; j <= count; ++j) {
      const double t_j = run_.samples[first_ + static_cast<size_t>(j)].t_s;
      const nav::NavState end = Mechanise(StartState(), count, [&](const ImuSample& smp, auto& g, auto& a) {
        if (smp.t_s == t_j) (axis < 3 ? g : a)[axis % 3] += size;
      });
      b[static_cast<size_t>(j)].col(axis) = ErrorBetween(end, nominal, site_) / size;
    }
  }
  struct Case {
    const char* what;
    Sensor sensor;
    int axis;
    std::optional<std::string> effect;  // none: the axis' Gauss–Markov drift
    double tau_s;
  };
  const Case cases[] = {
      {"slow gyro drift", Sensor::kGyro, 0, std::nullopt, 1000.0},
      {"fast accelerometer drift", Sensor::kAccelerometer, 1, std::nullopt, 0.05},
      {"gyro walk", Sensor::kGyro, 2, "gyro_bias_rw.z", 0.0},
      {"accelerometer second-order pair", Sensor::kAccelerometer, 0, "acc_bias_second_order.x", 0.0},
  };
  for (const Case& c : cases) {
    ErrorModel model;  // nothing else makes noise: Q is this state's alone
    model.reference = model_.reference;
    int state = 0;
    if (c.effect.has_value()) {
      ModelEffect e;
      e.term = ParseEffectSelector(*c.effect)->front();
      e.random_walk_density = 1e-4;
      e.second_order_sigma = 1e-3;
      e.second_order_alpha_per_s = 1.0 / 3.0;
      e.second_order_beta_rad_s = 2.0 * std::numbers::pi / 0.7;
      model.effects.push_back(e);
      state = StateLayout(model).EffectOffset(0) - StateLayout::kNavigationSize;
    } else {
      (c.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[static_cast<size_t>(c.axis)] = {1e-3, c.tau_s};
      state = SensorAxisIndex(c.sensor, c.axis);
    }
    const StateLayout layout(model);
    SensorBlocks d_sample, q_sample;
    SensorBlocks::Discretise(model, layout, dt, d_sample, q_sample);
    const SensorBlocks::Block* d = nullptr;
    const SensorBlocks::Block* q = nullptr;
    for (size_t k = 0; k < d_sample.blocks.size(); ++k) {
      if (d_sample.blocks[k].offset == state) d = &d_sample.blocks[k], q = &q_sample.blocks[k];
    }
    ASSERT_NE(d, nullptr);
    const int size = d->size;
    const Eigen::MatrixXd D = d->m.topLeftCorner(size, size);
    const double q_sample_var = q->m(0, 0);
    const std::vector<SensorBlocks::SampleMean> means =
        SensorBlocks::SampleMeans(model, layout, dt);
    const SensorBlocks::SampleMean& mean = means[static_cast<size_t>(d - d_sample.blocks.data())];
    // Exact sums. Sample j carries e₀ᵀ(Ψ x_{j−1} + v_j), v_j = G w_j + r_j:
    // B = Σ_j b_j e₀ᵀΨ D^{j−1}; the noise w_i of sample i reaches the epoch
    // through β_i = b_i e₀ᵀG + Σ_{j>i} b_j e₀ᵀΨ D^{j−1−i} and the state through
    // D^{M−i}; r_i through b_i alone.
    const int a = SensorAxisIndex(c.sensor, c.axis);
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(9, size), Qns = Eigen::MatrixXd::Zero(9, size);
    Eigen::MatrixXd Qnn = Eigen::MatrixXd::Zero(9, 9);
    Eigen::RowVectorXd e0 = Eigen::RowVectorXd::Zero(size);
    e0[0] = 1.0;
    const Eigen::RowVectorXd e0_psi = e0 * mean.transition.topLeftCorner(size, size);
    const Eigen::RowVectorXd e0_g = e0 * mean.cross.topLeftCorner(size, size) / q_sample_var;
    const double r_var = mean.noise(0, 0) - q_sample_var * e0_g.squaredNorm();
    for (int j = 1; j <= count; ++j) {
      B += b[static_cast<size_t>(j)].col(a) * (e0_psi * MatrixPower(D, j - 1));
    }
    for (int i = 1; i <= count; ++i) {
      Eigen::MatrixXd beta = b[static_cast<size_t>(i)].col(a) * e0_g;
      for (int j = i + 1; j <= count; ++j) {
        beta += b[static_cast<size_t>(j)].col(a) * (e0_psi * MatrixPower(D, j - 1 - i));
      }
      Qnn +=
          q_sample_var * beta * beta.transpose() +
          r_var * b[static_cast<size_t>(i)].col(a) * b[static_cast<size_t>(i)].col(a).transpose();
      Qns += q_sample_var * beta * MatrixPower(D, count - i).transpose();
    }
    const IntervalTransition t = Transition(model, count);
    const double b_scale = B.cwiseAbs().maxCoeff();
    const double qns_scale = Qns.cwiseAbs().maxCoeff();
    const double qnn_scale = Qnn.cwiseAbs().maxCoeff();
    for (int r = 0; r < 9; ++r) {
      for (int k = 0; k < size; ++k) {
        EXPECT_NEAR(t.B(r, state + k), B(r, k), 2e-3 * b_scale) << c.what << " B row " << r;
        EXPECT_NEAR(t.Qns(r, state + k), Qns(r, k), 2e-3 * qns_scale) << c.what << " Qns row " << r;
      }
      for (int k = 0; k < 9; ++k) {
        EXPECT_NEAR(t.Qnn(r, k), Qnn(r, k), 2e-3 * qnn_scale) << c.what << " Qnn " << r << "," << k;
      }
    }
  }
}

}  // namespace
}  // namespace insdiag::engine

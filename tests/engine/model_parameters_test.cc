// A model's named parameters state it completely: a report's model is the
// model the analysis ran, and a later analysis of the same run starts from
// it (engine/model/parameters.h, api::IdentifiedModelOf).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/parameter_field.h"
#include "insdiag/engine/model/parameters.h"

namespace insdiag::engine {
namespace {

ModelEffect EffectOrDie(const std::string& name) {
  auto terms = ParseEffectSelector(name);
  EXPECT_TRUE(terms.ok() && terms->size() == 1) << name;
  ModelEffect e;
  e.term = terms->front();
  return e;
}

// A model with every kind of parameter, its values drawn at random.
ErrorModel RandomModel(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.5, 2.0);
  ErrorModel m;
  for (SensorTriadModel* t : {&m.gyro, &m.acc}) {
    for (GaussMarkov& b : t->bias) b = {.sigma = 1e-7 * u(rng), .tau_s = 1800.0 * u(rng)};
    t->white_noise_density = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1e-6;
    t->quantization = Eigen::Vector3d(u(rng), 0.0, u(rng)) * 1e-7;
  }
  m.reference = {.attitude_sigma_rad = 5e-6 * u(rng), .position_sigma_m = 1e-6 * u(rng),
                 .velocity_sigma_mps = 1e-7 * u(rng)};
  ModelEffect scale = EffectOrDie("gyro_scale_factor.z");
  scale.prior_sigma[0] = 1e-5 * u(rng);
  ModelEffect harmonic = EffectOrDie("gyro_yaw_harmonic.x");
  harmonic.prior_sigma = {1e-7 * u(rng), 2e-7 * u(rng)};
  ModelEffect step = EffectOrDie("gyro_bias_step.y");
  step.prior_sigma[0] = 1e-6 * u(rng);
  step.onset_s = 1500.0 * u(rng);
  ModelEffect ramp = EffectOrDie("acc_bias_ramp.z");
  ramp.prior_sigma[0] = 1e-8 * u(rng);
  ramp.onset_s = 600.0 * u(rng);
  ModelEffect walk = EffectOrDie("acc_bias_rw.x");
  walk.random_walk_density = 1e-7 * u(rng);
  ModelEffect pair = EffectOrDie("gyro_bias_second_order.z");
  pair.second_order_sigma = 1e-7 * u(rng);
  pair.second_order_alpha_per_s = 1.0 / (300.0 * u(rng));
  pair.second_order_beta_rad_s = 2.0 * std::numbers::pi / (900.0 * u(rng));
  m.effects = {scale, harmonic, step, ramp, walk, pair};
  return m;
}

TEST(ModelParameters, SettingThemAllOnAnEmptyModelGivesTheModelBack) {
  std::mt19937_64 rng(20261125);
  for (int trial = 0; trial < 20; ++trial) {
    const ErrorModel model = RandomModel(rng);
    ErrorModel again;
    for (const NamedParameter& p : ParametersOf(model)) {
      ASSERT_TRUE(SetParameter(p.name, p.value, again).ok()) << p.name;
    }
    // A second-order term states τ = 1/α and period 2π/β: those two come back to rounding.
    ASSERT_EQ(again.effects.size(), model.effects.size());
    ModelEffect& pair = again.effects.back();
    EXPECT_NEAR(pair.second_order_alpha_per_s, model.effects.back().second_order_alpha_per_s,
                1e-15 * model.effects.back().second_order_alpha_per_s);
    EXPECT_NEAR(pair.second_order_beta_rad_s, model.effects.back().second_order_beta_rad_s,
                1e-15 * model.effects.back().second_order_beta_rad_s);
    pair.second_order_alpha_per_s = model.effects.back().second_order_alpha_per_s;
    pair.second_order_beta_rad_s = model.effects.back().second_order_beta_rad_s;
    EXPECT_TRUE(again == model) << "trial " << trial;
  }
}

TEST(ModelParameters, NameTheirUnits) {
  EXPECT_EQ(ParameterUnit("reference.position_sigma"), "m");
  EXPECT_EQ(ParameterUnit("gyro_bias_step.x.onset"), "s");
  EXPECT_EQ(ParameterUnit("gyro_bias_gm.x.sigma"), "rad/s");
}

TEST(ModelParameters, ADriftsParametersAreNamedAndFoundInOnePlace) {
  const DriftAxis acc_y{Sensor::kAccelerometer, 1};
  EXPECT_EQ(DriftSigmaName(acc_y), "acc_bias_gm.y.sigma");
  EXPECT_EQ(DriftTauName(acc_y), "acc_bias_gm.y.tau");
  for (const DriftAxis d : DriftAxis::All()) {
    EXPECT_EQ(DriftOfParameter(DriftSigmaName(d)), d);
    EXPECT_EQ(DriftOfParameter(DriftTauName(d)), d);
  }
  for (const char* other :
       {"gyro_bias_gm.x", "gyro_bias_rw.x.density", "gyro_bias_second_order.x.sigma",
        "acc_bias_gm.w.sigma", "gyro_arw.x", ""}) {
    EXPECT_FALSE(DriftOfParameter(other).has_value()) << other;
  }
  // The model's parameter list names its drifts so.
  ErrorModel m;
  m.acc.bias[1] = {3e-4, 900.0};
  ASSERT_TRUE(SetParameter(DriftTauName(acc_y), 1200.0, m).ok());
  EXPECT_EQ(DriftOf(m, acc_y).tau_s, 1200.0);
}

TEST(ModelParameters, AFieldIsSplitOffANameAndPutBackTheSameWay) {
  for (const ParameterField field :
       {ParameterField::kPriorSigma, ParameterField::kOnset, ParameterField::kDensity,
        ParameterField::kSigma, ParameterField::kTau, ParameterField::kPeriod,
        ParameterField::kDecayRate, ParameterField::kFrequency}) {
    const std::string name = ParameterName("gyro_bias_second_order.y", field);
    const SplitParameter split = SplitParameterName(name);
    EXPECT_EQ(split.quantity, "gyro_bias_second_order.y") << name;
    EXPECT_EQ(split.field, field) << name;
  }
  // A term's own axis or harmonic is not a field.
  for (const char* whole : {"gyro_scale_factor.z", "gyro_yaw_harmonic.x.sin", "sigma", ".tau"}) {
    EXPECT_EQ(SplitParameterName(whole).field, ParameterField::kValue) << whole;
    EXPECT_EQ(SplitParameterName(whole).quantity, whole);
  }
  EXPECT_EQ(ParameterName("gyro_scale_factor.z", ParameterField::kValue), "gyro_scale_factor.z");
  // A second-order process set by its fit's α and β reads back as τ and period.
  ErrorModel m;
  ASSERT_TRUE(
      SetParameter(ParameterName("gyro_bias_second_order.y", ParameterField::kDecayRate), 0.01, m)
          .ok());
  ASSERT_TRUE(
      SetParameter(ParameterName("gyro_bias_second_order.y", ParameterField::kFrequency), 0.1, m)
          .ok());
  int read_back = 0;
  for (const NamedParameter& p : ParametersOf(m)) {
    if (p.name == "gyro_bias_second_order.y.tau") {
      EXPECT_NEAR(p.value, 100.0, 1e-9);
      ++read_back;
    }
    if (p.name == "gyro_bias_second_order.y.period") {
      EXPECT_NEAR(p.value, 2.0 * std::numbers::pi / 0.1, 1e-9);
      ++read_back;
    }
  }
  EXPECT_EQ(read_back, 2);
}

TEST(ModelParameters, RefuseWhatTheyCannotBe) {
  ErrorModel m;
  EXPECT_FALSE(SetParameter("reference.position_sigma", 0.0, m).ok());
  EXPECT_FALSE(SetParameter("gyro_scale_factor.z.onset", 10.0, m).ok()) << "a constant effect has no onset";
  EXPECT_FALSE(SetParameter("reference.heading", 1.0, m).ok());
  EXPECT_TRUE(m == ErrorModel{}) << "a refused parameter changed the model";
}

}  // namespace
}  // namespace insdiag::engine

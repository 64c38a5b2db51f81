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
#include "insdiag/engine/model/parameter_key.h"
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
  m.acc.flicker[1] = {.coefficient = 1e-4 * u(rng), .shortest_tau_s = 2.0 * u(rng), .longest_tau_s = 3000.0 * u(rng)};
  m.reference = {.attitude_sigma_rad = 5e-6 * u(rng),
                 .horizontal_position_sigma_m = 1e-6 * u(rng),
                 .vertical_position_sigma_m = 2e-6 * u(rng),
                 .horizontal_velocity_sigma_mps = 1e-7 * u(rng),
                 .vertical_velocity_sigma_mps = 2e-7 * u(rng)};
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
  EXPECT_EQ(ParameterUnit("reference.vertical_position_sigma"), "m");
  EXPECT_EQ(ParameterUnit("reference.position_sigma"), "m");
  EXPECT_EQ(ParameterUnit("gyro_bias_step.x.onset"), "s");
  EXPECT_EQ(ParameterUnit("gyro_bias_gm.x.sigma"), "rad/s");
  EXPECT_EQ(ParameterUnit("acc_bias_instability.y"), "m/s^2");
  EXPECT_EQ(ParameterUnit("gyro_bias_instability.z.tau_min"), "s");
  EXPECT_EQ(ParameterUnit("gyro_bias_instability.z.tau_max"), "s");
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

// Models stored before the reference's accuracy was stated across and
// along the vertical name one σ for both; they load with it on both.
TEST(ModelParameters, OneReferenceSigmaOfAStoredModelSetsBothAxes) {
  ErrorModel m;
  ASSERT_TRUE(SetParameter("reference.position_sigma", 2e-3, m).ok());
  ASSERT_TRUE(SetParameter("reference.velocity_sigma", 3e-4, m).ok());
  EXPECT_EQ(m.reference.horizontal_position_sigma_m, 2e-3);
  EXPECT_EQ(m.reference.vertical_position_sigma_m, 2e-3);
  EXPECT_EQ(m.reference.horizontal_velocity_sigma_mps, 3e-4);
  EXPECT_EQ(m.reference.vertical_velocity_sigma_mps, 3e-4);
}

TEST(ModelParameters, RefuseWhatTheyCannotBe) {
  ErrorModel m;
  EXPECT_FALSE(SetParameter("reference.position_sigma", 0.0, m).ok());
  EXPECT_FALSE(SetParameter("reference.vertical_velocity_sigma", -1.0, m).ok());
  EXPECT_FALSE(SetParameter("gyro_scale_factor.z.onset", 10.0, m).ok()) << "a constant effect has no onset";
  EXPECT_FALSE(SetParameter("reference.heading", 1.0, m).ok());
  EXPECT_TRUE(m == ErrorModel{}) << "a refused parameter changed the model";
}

// A name is parsed once into its sensor, family, axes and field; every name
// a model states parses, and reads the sensor axis its drift or term reads.
TEST(ParameterKey, ParsesEveryNameAModelStates) {
  std::mt19937_64 rng(7);
  for (const NamedParameter& p : ParametersOf(RandomModel(rng))) {
    const std::optional<ParameterKey> key = ParseParameterKey(p.name);
    ASSERT_TRUE(key.has_value()) << p.name;
    const bool reference = p.name.starts_with("reference.");
    EXPECT_EQ(key->sensor.has_value(), !reference) << p.name;
    if (!reference) {
      EXPECT_GE(key->axis, 0) << p.name;
      EXPECT_EQ(p.name.starts_with(key->Quantity()), true) << p.name;
    }
  }
}

TEST(ParameterKey, SplitsSensorFamilyAxesAndField) {
  const auto sigma = ParseParameterKey("acc_bias_gm.y.sigma");
  ASSERT_TRUE(sigma.has_value());
  EXPECT_EQ(sigma->family, "acc_bias_gm");
  EXPECT_EQ(sigma->sensor, Sensor::kAccelerometer);
  EXPECT_EQ(sigma->axes, "y");
  EXPECT_EQ(sigma->field, ParameterField::kSigma);
  EXPECT_EQ(sigma->SensorAxis(), "acc.y");
  EXPECT_EQ(sigma->Drift(), (DriftAxis{Sensor::kAccelerometer, 1}));
  EXPECT_EQ(sigma->effect_family, nullptr) << "the base drift is no catalogue effect";

  const auto pair = ParseParameterKey("gyro_misalignment.zx");
  ASSERT_TRUE(pair.has_value());
  EXPECT_EQ(pair->axis, 2);
  EXPECT_EQ(pair->source_axis, 0);
  EXPECT_EQ(pair->SensorAxis(), "gyro.z") << "a pair reads into its output axis";
  EXPECT_EQ(pair->effect_family, FindEffectFamily("gyro_misalignment"));
  EXPECT_TRUE(pair->IsBareTerm());

  const auto harmonic = ParseParameterKey("gyro_yaw_harmonic.x.cos.prior_sigma");
  ASSERT_TRUE(harmonic.has_value());
  EXPECT_EQ(harmonic->harmonic, 1);
  EXPECT_EQ(harmonic->field, ParameterField::kPriorSigma);
  EXPECT_EQ(harmonic->Quantity(), "gyro_yaw_harmonic.x");

  const auto fault = ParseParameterKey("gyro_bias_step.y@1500");
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->onset_s, 1500.0);
  EXPECT_EQ(fault->Quantity(), "gyro_bias_step.y");

  const auto family = ParseParameterKey("acc_scale_factor.*");
  ASSERT_TRUE(family.has_value());
  EXPECT_TRUE(family->IsFamilyPattern());
  EXPECT_EQ(family->axis, -1);
  EXPECT_EQ(family->SensorAxis(), "");

  const auto reference = ParseParameterKey("reference.attitude_sigma");
  ASSERT_TRUE(reference.has_value());
  EXPECT_FALSE(reference->sensor.has_value());
  EXPECT_EQ(reference->Quantity(), "reference.attitude_sigma");
}

TEST(ParameterKey, RefusesWhatIsNoName) {
  for (const char* name : {"", ".x", "gyro_scale_factor.w", "gyro_scale_factor.xyz",
                           "gyro_bias_step.x@soon", "gyro_bias_step.x@inf"}) {
    EXPECT_FALSE(ParseParameterKey(name).has_value()) << name;
  }
  EXPECT_EQ(AxisName(2), "z");
  EXPECT_EQ(AxisName(3), "");
}

}  // namespace
}  // namespace insdiag::engine

// insdiag simulate OUT.csv [--profile NAME] [--effect NAME=VALUE]... [--seed N] …
// Writes a bench run of a simulated unit on a two-axis rotary table, with the
// given effects (and faults) hidden in it. The unit's base model is its unit
// type's nominal model (data/unit-types), so no sensor number lives here.
#include <cmath>
#include <numbers>
#include <ostream>

#include "insdiag/api/unit_types.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/model/parameters.h"
#include "insdiag/engine/sim/simulator.h"
#include "insdiag/engine/status_macros.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Exactly `count` comma-separated numbers.
absl::StatusOr<std::vector<double>> Numbers(std::string_view text, const std::string& what, size_t count) {
  auto out = engine::sim::ParseNumberList(text, what);
  if (out.ok() && out->size() != count) {
    return absl::InvalidArgumentError(what + ": expected " + std::to_string(count) + " comma-separated numbers");
  }
  return out;
}

// "gyro.x=TIME,SIZE" → sensor, axis and the two numbers.
absl::Status ParseFault(const std::string& spec, const std::string& flag, engine::Sensor* sensor, int* axis,
                        double* time_s, double* size) {
  const size_t eq = spec.find('=');
  const std::string target = spec.substr(0, eq);
  if (eq == std::string::npos || (target.size() != 5 && target.size() != 6)) {
    return absl::InvalidArgumentError(flag + " " + spec + ": expected gyro.x|acc.y…=TIME_S,SIZE");
  }
  const bool gyro = target.rfind("gyro.", 0) == 0;
  const bool acc = target.rfind("acc.", 0) == 0;
  const char a = target.back();
  if (!(gyro || acc) || a < 'x' || a > 'z') {
    return absl::InvalidArgumentError(flag + " " + spec + ": the target is gyro.x … acc.z");
  }
  INSDIAG_ASSIGN_OR_RETURN(auto v,
                           Numbers(std::string_view(spec).substr(eq + 1), flag + " " + spec, 2));
  *sensor = gyro ? engine::Sensor::kGyro : engine::Sensor::kAccelerometer;
  *axis = a - 'x';
  *time_s = (v)[0];
  *size = (v)[1];
  return absl::OkStatus();
}

class SimulateVerb final : public Verb {
 public:
  std::string Name() const override { return "simulate"; }
  std::string Summary() const override {
    return "Write a bench run of a simulated unit on a rotary table, with effects hidden in it";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("OUT.csv", &file_, "Bench-run file to write");
    options.Option("--profile", &profile_,
                   "Table profile: static, rotations, positions, thermal, full or drift (default full, two hours: excites "
                   "every constant effect of the catalogue and the second-order drifts; a bias random walk needs the "
                   "eight hours of drift)");
    options.Repeated("--effect", &effects_,
                     "Hidden effect NAME=VALUE, e.g. gyro_scale_factor.z=1e-4 (a family applies to every axis; "
                     "yaw harmonics SIN[,COS]; bias_rw K; bias_second_order SIGMA,TAU_S,PERIOD_S; warm_up START,TAU_S; faults VALUE@ONSET_S)");
    options.Option("--seed", &seed_, "Random seed (default 1)");
    options.Option("--rate", &rate_, "Sample rate in Hz (default 50)");
    options.Option("--unit-type", &unit_type_, "Unit type whose nominal model the unit has (default INS-2000)");
    options.Repeated("--param", &params_,
                     "Override a base-model parameter NAME=VALUE, e.g. gyro_bias_gm.x.sigma=1.5e-7 or "
                     "acc_quantization.z=3.5e-4 (SI units)");
    options.Repeated("--bias-step", &steps_, "Fault: drift step gyro.x|…|acc.z=TIME_S,SIZE (rad/s or m/s²)");
    options.Repeated("--spike", &spikes_, "Fault: one-sample spike gyro.x|…|acc.z=TIME_S,SIZE");
    options.Option("--serial", &serial_, "Unit serial written to the file (default SIM-<seed>)");
    options.Option("--site", &site_, "Site LAT_DEG,LON_DEG,HEIGHT_M (default 55.5672,38.15,125)");
    options.Flag("--no-datasheet", &no_datasheet_,
                 "Leave the datasheet metadata (the unit type's specification, not the --param values) out of the "
                 "file");
  }

  int Run(std::ostream& out, std::ostream& err) override {
    auto st = Simulate(out);
    if (!st.ok()) {
      err << "insdiag simulate: " << st.message() << "\n";
      return st.code() == absl::StatusCode::kInvalidArgument ? kExitUsage : kExitRefused;
    }
    return kExitOk;
  }

 private:
  absl::Status Simulate(std::ostream& out) {
    INSDIAG_ASSIGN_OR_RETURN(auto profile, engine::sim::BuiltinProfile(profile_));
    auto unit_type = api::BuiltinUnitType(unit_type_);
    if (!unit_type.ok()) return absl::InvalidArgumentError(std::string(unit_type.status().message()));
    INSDIAG_ASSIGN_OR_RETURN(auto model, api::BaseModelOf(*unit_type));
    // The datasheet states the unit type's specification; --param makes this
    // unit depart from it.
    const engine::Datasheet specification = engine::sim::DatasheetOf(model.gyro, model.acc);
    for (const std::string& p : params_) {
      const size_t eq = p.find('=');
      INSDIAG_ASSIGN_OR_RETURN(
          auto value, Numbers(eq == std::string::npos ? "" : std::string_view(p).substr(eq + 1),
                              "--param " + p, 1));
      engine::ErrorModel probe;
      INSDIAG_RETURN_IF_ERROR(engine::SetParameter(p.substr(0, eq), (value)[0], probe));
      if (!probe.effects.empty()) {
        return absl::InvalidArgumentError("--param " + p + ": effects are hidden with --effect");
      }
      INSDIAG_RETURN_IF_ERROR(engine::SetParameter(p.substr(0, eq), (value)[0], model));
    }
    engine::sim::SimulatedUnit unit;
    unit.type = unit_type->display_name();
    unit.gyro = model.gyro;
    unit.acc = model.acc;
    for (const std::string& e : effects_) {
      INSDIAG_ASSIGN_OR_RETURN(auto parsed, engine::sim::ParseTrueEffect(e));
      unit.effects.insert(unit.effects.end(), parsed.begin(), parsed.end());
    }
    for (const std::string& s : steps_) {
      engine::sim::BiasStep step;
      if (auto st = ParseFault(s, "--bias-step", &step.sensor, &step.axis, &step.time_s, &step.size); !st.ok()) {
        return st;
      }
      unit.bias_steps.push_back(step);
    }
    for (const std::string& s : spikes_) {
      engine::sim::Spike spike;
      if (auto st = ParseFault(s, "--spike", &spike.sensor, &spike.axis, &spike.time_s, &spike.size); !st.ok()) {
        return st;
      }
      unit.spikes.push_back(spike);
    }
    engine::sim::SimulationOptions options;
    auto seed = Numbers(seed_, "--seed", 1);
    auto rate = Numbers(rate_, "--rate", 1);
    auto site = Numbers(site_, "--site", 3);
    for (const auto* v : {&seed, &rate, &site}) {
      if (!v->ok()) return v->status();
    }
    if ((*seed)[0] < 0 || (*seed)[0] != std::floor((*seed)[0])) {
      return absl::InvalidArgumentError("--seed: a non-negative integer");
    }
    options.seed = static_cast<uint64_t>((*seed)[0]);
    options.sample_rate_hz = (*rate)[0];
    options.site = {(*site)[0] * kDeg, (*site)[1] * kDeg, (*site)[2]};
    options.write_datasheet = !no_datasheet_;
    options.datasheet = specification;
    unit.serial = serial_.empty() ? "SIM-" + std::to_string(options.seed) : serial_;
    INSDIAG_ASSIGN_OR_RETURN(auto sim, engine::sim::Simulate(unit, profile, options));
    INSDIAG_RETURN_IF_ERROR(benchrun::WriteBenchRunFile(sim.run, file_));
    out << file_ << ": " << sim.run.samples.size() << " samples, " << sim.run.DurationS()
        << " s, profile " << profile.name << ", unit " << unit.serial << " (" << unit.type
        << "), seed " << options.seed << "\n";
    return absl::OkStatus();
  }

  std::string file_;
  std::string profile_ = "full";
  std::vector<std::string> effects_;
  std::string seed_ = "1";
  std::string rate_ = "50";
  std::string unit_type_ = "INS-2000";
  std::vector<std::string> params_;
  std::vector<std::string> steps_;
  std::vector<std::string> spikes_;
  std::string serial_;
  std::string site_ = "55.5672,38.15,125";
  bool no_datasheet_ = false;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_simulate() { return std::make_unique<SimulateVerb>(); }

}  // namespace insdiag::cli

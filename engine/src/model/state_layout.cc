#include "insdiag/engine/model/state_layout.h"

#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/flicker_floor.h"

namespace insdiag::engine {
namespace {

constexpr const char* kNedAxes[] = {"n", "e", "d"};
constexpr const char* kBodyAxes[] = {"x", "y", "z"};

}  // namespace

StateLayout::StateLayout(const ErrorModel& model) {
  int next = kNavigationSize;
  auto add = [&](SensorState s) {
    s.index = next++;
    sensor_states_.push_back(std::move(s));
  };
  auto add_drift = [&](Sensor sensor, const char* family, int axis) {
    SensorState s;
    s.name = std::string(family) + "." + kBodyAxes[axis];
    s.sensor = sensor;
    s.axis = axis;
    s.dynamics = StateDynamics::kGaussMarkov;
    add(std::move(s));
  };
  gyro_bias_ = next;
  for (int i = 0; i < 3; ++i) add_drift(Sensor::kGyro, "gyro_bias_gm", i);
  acc_bias_ = next;
  for (int i = 0; i < 3; ++i) add_drift(Sensor::kAccelerometer, "acc_bias_gm", i);
  for (const Sensor sensor : {Sensor::kGyro, Sensor::kAccelerometer}) {
    const SensorTriadModel& triad = sensor == Sensor::kGyro ? model.gyro : model.acc;
    for (int i = 0; i < 3; ++i) {
      const int components = FlickerComponentCount(triad.flicker[static_cast<size_t>(i)]);
      for (int j = 0; j < components; ++j) {
        SensorState s;
        s.name = FlickerName({sensor, i}) + "." + std::to_string(j + 1);
        s.sensor = sensor;
        s.axis = i;
        s.parameter = j;
        s.dynamics = StateDynamics::kFlickerComponent;
        add(std::move(s));
      }
    }
  }
  for (size_t k = 0; k < model.effects.size(); ++k) {
    const EffectTerm& term = model.effects[k].term;
    const int effect = static_cast<int>(k);
    effect_offsets_.push_back(next);
    SensorState base;
    base.sensor = term.family->sensor;
    base.axis = term.axis;
    base.effect = effect;
    switch (term.family->process) {
      case RandomProcess::kNone:
        for (int p = 0; p < term.family->parameters_per_term; ++p) {
          SensorState s = base;
          s.name = term.ParameterName(p);
          s.parameter = p;
          s.dynamics = StateDynamics::kConstant;
          add(s);
        }
        break;
      case RandomProcess::kRandomWalk: {
        SensorState s = base;
        s.name = term.Name();
        s.dynamics = StateDynamics::kRandomWalk;
        add(s);
        break;
      }
      case RandomProcess::kDecayFromStart: {
        SensorState s = base;
        s.name = term.Name();
        s.dynamics = StateDynamics::kDecaying;
        add(s);
        break;
      }
      case RandomProcess::kSecondOrderMarkov: {
        SensorState first = base;
        first.name = term.Name() + ".1";
        first.dynamics = StateDynamics::kSecondOrderPair;
        add(first);
        SensorState second = base;
        second.name = term.Name() + ".2";
        second.parameter = 1;
        second.reaches_output = false;
        second.dynamics = StateDynamics::kSecondOrderTail;
        add(second);
        break;
      }
    }
  }
  size_ = next;
}

std::string StateLayout::StateName(int i) const {
  if (i < attitude_ + 3) return std::string("att.") + kNedAxes[i - attitude_];
  if (i < velocity_ + 3) return std::string("vel.") + kNedAxes[i - velocity_];
  if (i < position_ + 3) return std::string("pos.") + kNedAxes[i - position_];
  return sensor_states_[static_cast<size_t>(i - kNavigationSize)].name;
}

}  // namespace insdiag::engine

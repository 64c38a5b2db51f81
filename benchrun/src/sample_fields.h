// Access to the values of an ImuSample by SampleField, for the code that walks
// all fields of a sample (reader, writer, validator).
#pragma once

#include <array>
#include <span>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/engine/bench_run.h"

namespace insdiag::benchrun::internal {

inline constexpr std::array<SampleField, kSampleFieldCount> kAllSampleFields = {
    SampleField::kT,        SampleField::kGyroX,  SampleField::kGyroY, SampleField::kGyroZ,
    SampleField::kAccX,     SampleField::kAccY,   SampleField::kAccZ,  SampleField::kRefRoll,
    SampleField::kRefPitch, SampleField::kRefYaw, SampleField::kTemp,
};

// The fields a run's samples carry, in column order: temp only with temperature.
inline std::span<const SampleField> FieldsOf(bool has_temperature) {
  return std::span<const SampleField>(kAllSampleFields)
      .first(has_temperature ? kSampleFieldCount : kSampleFieldCount - 1);
}

// The value of `field` in `sample`; a reference into it (const when the sample is).
template <typename Sample>  // engine::ImuSample or const engine::ImuSample
auto& ValueOf(Sample& sample, SampleField field) {
  switch (field) {
    case SampleField::kT:
      return sample.t_s;
    case SampleField::kGyroX:
      return sample.gyro_rad_s.x();
    case SampleField::kGyroY:
      return sample.gyro_rad_s.y();
    case SampleField::kGyroZ:
      return sample.gyro_rad_s.z();
    case SampleField::kAccX:
      return sample.acc_mps2.x();
    case SampleField::kAccY:
      return sample.acc_mps2.y();
    case SampleField::kAccZ:
      return sample.acc_mps2.z();
    case SampleField::kRefRoll:
      return sample.ref_rpy_rad.x();
    case SampleField::kRefPitch:
      return sample.ref_rpy_rad.y();
    case SampleField::kRefYaw:
      return sample.ref_rpy_rad.z();
    case SampleField::kTemp:
      break;
  }
  return sample.temp_degc;
}

}  // namespace insdiag::benchrun::internal

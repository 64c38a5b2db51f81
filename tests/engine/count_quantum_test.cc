// The counting quantum read from a run's samples (ident/count_quantum.h).
#include "insdiag/engine/ident/count_quantum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace insdiag::engine::ident {
namespace {

constexpr double kIntervalS = 0.01;  // 100 Hz: not a binary fraction, as real loggers' are not

// A still unit whose accelerometers are integrating counters of quantum
// `quantum_mps`, each started at a random residue: the sample is the change
// of the counter over its interval, as a rate.
BenchRun CountedRun(double quantum_mps, const Eigen::Vector3d& specific_force_mps2, double noise_mps2, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_mps2);
  std::uniform_real_distribution<double> residue(0.0, 1.0);
  BenchRun run;
  Eigen::Vector3d total_counts(residue(rng), residue(rng), residue(rng));
  Eigen::Vector3d reported = total_counts.array().floor();
  for (int k = 0; k < 20'000; ++k) {
    ImuSample s;
    s.t_s = (k + 1) * kIntervalS;
    for (int a = 0; a < 3; ++a) total_counts[a] += (specific_force_mps2[a] + noise(rng)) * kIntervalS / quantum_mps;
    const Eigen::Vector3d now = total_counts.array().floor();
    s.acc_mps2 = (now - reported) * quantum_mps / kIntervalS;
    reported = now;
    s.gyro_rad_s = Eigen::Vector3d(noise(rng), noise(rng), noise(rng));  // continuous
    run.samples.push_back(s);
  }
  return run;
}

std::optional<double> QuantumOf(const BenchRun& run, Sensor sensor, int axis) {
  return CountQuanta(run)[static_cast<size_t>(DriftAxis{sensor, axis}.Index())];
}

TEST(CountQuantum, IsReadFromACountedOutputOnEveryAxis) {
  constexpr double kQuantumMps = 125e-6 * 9.80665;  // 125 µg·s, a navigation-grade accelerometer's count
  // z along gravity at exactly 98 quanta a sample with noise of a hundredth
  // of one: it reads 98 and now and then 97 or 99 — its own smallest spacing
  // is still one quantum, but x, near zero, spans few values.
  const Eigen::Vector3d force(0.02, -0.3, -98.0 * kQuantumMps / kIntervalS);
  const BenchRun run = CountedRun(kQuantumMps, force, 0.01 * kQuantumMps / kIntervalS, 1);
  for (int axis = 0; axis < 3; ++axis) {
    const auto q = QuantumOf(run, Sensor::kAccelerometer, axis);
    ASSERT_TRUE(q.has_value()) << "axis " << axis;
    EXPECT_NEAR(*q, kQuantumMps, 1e-9 * kQuantumMps) << "axis " << axis;
  }
}

TEST(CountQuantum, TwoValuesTwoQuantaApartTakeTheSensorsSpacing) {
  constexpr double kQuantumMps = 1e-3;
  BenchRun run = CountedRun(kQuantumMps, Eigen::Vector3d(0.05, 0.2, -9.8), 0.5, 2);
  // Only even counts on x: alone, its spacing would read two quanta.
  for (ImuSample& s : run.samples) s.acc_mps2.x() = (s.t_s < 100.0 ? -2.0 : 2.0) * kQuantumMps / kIntervalS;
  const auto q = QuantumOf(run, Sensor::kAccelerometer, 0);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(*q, kQuantumMps, 1e-12);
}

TEST(CountQuantum, AContinuousOrConstantOutputHasNone) {
  BenchRun run = CountedRun(1e-3, Eigen::Vector3d(0.05, 0.2, -9.8), 0.5, 3);
  for (int axis = 0; axis < 3; ++axis) EXPECT_FALSE(QuantumOf(run, Sensor::kGyro, axis).has_value()) << axis;
  // One value: alone it has no spacing; on the lattice of the sensor's
  // other axes it is a count (an axis along gravity may read one count
  // throughout), off it not.
  for (ImuSample& s : run.samples) s.acc_mps2.y() = -98.0 * 1e-3 / kIntervalS;
  EXPECT_TRUE(QuantumOf(run, Sensor::kAccelerometer, 1).has_value());
  for (ImuSample& s : run.samples) s.acc_mps2.y() = -98.4 * 1e-3 / kIntervalS;
  EXPECT_FALSE(QuantumOf(run, Sensor::kAccelerometer, 1).has_value());
  // A counted output with one sample off the lattice (a logger's glitch) is
  // not counted: the lattice is exact or absent.
  run.samples[777].acc_mps2.z() += 0.3e-3 / kIntervalS;
  EXPECT_FALSE(QuantumOf(run, Sensor::kAccelerometer, 2).has_value());
}

}  // namespace
}  // namespace insdiag::engine::ident

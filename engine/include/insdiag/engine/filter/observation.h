// The observation channels of the bench (seed eq. 7): z = nav_INS − nav_ref,
// where the reference is the surveyed site, zero velocity and, while the
// table stands still, the table's encoder attitude.
//
//   lat     (φ_INS − φ_site)(R_M + h)          m, north      h-row: +δr_N
//   lon     (λ_INS − λ_site)(R_N + h) cos φ    m, east       h-row: +δr_E
//   height  h_INS − h_site                      m, up         h-row: −δr_D
//   vel_n, vel_e, vel_d   v_INS − 0              m/s, NED     h-row: +δv
//   att_n, att_e, att_d   ψ = Log(C_ref C̃ᵀ)      rad, NED     h-row: +ψ
//
// With C̃ = (I − [ψ×]) C (state_layout.h), C_ref C̃ᵀ = I + [ψ×] to first
// order: the rotation vector of the reference attitude against the INS's is
// the attitude error itself (Savage, Strapdown Analytics, 2nd ed., §12.2.1:
// the attitude-difference measurement). The encoders are read at epochs the
// table spends at rest only: while it turns, a readout's time tag error of
// Δt reads as an attitude error of ω Δt (10 μrad for 1 ms at 0.6 °/s), which
// no model of the sensors explains. A bench that does not read the attitude
// (a vehicle, a levelled or given attitude: bench_run.h) observes the six
// position and velocity channels only.
//
// Position residuals are in metres along the meridian and the parallel so
// that every channel reads in SI units a factory engineer can compare.
#pragma once

#include <array>
#include <limits>
#include <numbers>
#include <string_view>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/nav/strapdown.h"

namespace insdiag::engine {

inline constexpr int kChannelCount = 9;
inline constexpr std::array<std::string_view, kChannelCount> kChannelNames = {
    "lat", "lon", "height", "vel_n", "vel_e", "vel_d", "att_n", "att_e", "att_d"};
inline constexpr std::array<std::string_view, kChannelCount> kChannelUnits = {"m",   "m",   "m",   "m/s", "m/s",
                                                                              "m/s", "rad", "rad", "rad"};
// The first channel of each group of three.
inline constexpr int kPositionChannel = 0;
inline constexpr int kVelocityChannel = 3;
inline constexpr int kAttitudeChannel = 6;
inline constexpr bool IsAttitudeChannel(int channel) { return channel >= kAttitudeChannel; }

// The attitude channels' noise floor when the encoders read exactly (a
// simulated table): the rounding of the attitude difference itself, a few
// thousand units in the last place of an angle of order π.
inline constexpr double kAttitudeRoundingRad = std::numeric_limits<double>::epsilon() * std::numbers::pi * 1e3;

// A channel's observation row: a single state times ±1.
struct ObservationRow {
  int state = 0;
  double sign = 1.0;
};

std::array<ObservationRow, kChannelCount> ObservationRows(const StateLayout& layout);

// z for every channel from the INS state, the site and the reference attitude C_ref = C_b^n.
std::array<double, kChannelCount> Observe(const nav::NavState& ins, const Site& site,
                                          const Eigen::Matrix3d& C_ref);

}  // namespace insdiag::engine

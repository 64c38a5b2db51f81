// The observation channels of the bench (seed eq. 7): z = nav_INS − nav_ref,
// where the reference is the surveyed site and zero velocity.
//
//   lat     (φ_INS − φ_site)(R_M + h)          m, north      h-row: +δr_N
//   lon     (λ_INS − λ_site)(R_N + h) cos φ    m, east       h-row: +δr_E
//   height  h_INS − h_site                      m, up         h-row: −δr_D
//   vel_n, vel_e, vel_d   v_INS − 0              m/s, NED     h-row: +δv
//
// Position residuals are in metres along the meridian and the parallel so
// that every channel reads in SI units a factory engineer can compare.
#pragma once

#include <array>
#include <string_view>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/nav/strapdown.h"

namespace insdiag::engine {

inline constexpr int kChannelCount = 6;
inline constexpr std::array<std::string_view, kChannelCount> kChannelNames = {"lat",   "lon",   "height",
                                                                              "vel_n", "vel_e", "vel_d"};
inline constexpr std::array<std::string_view, kChannelCount> kChannelUnits = {"m", "m", "m", "m/s", "m/s", "m/s"};

// A channel's observation row: a single state times ±1.
struct ObservationRow {
  int state = 0;
  double sign = 1.0;
};

std::array<ObservationRow, kChannelCount> ObservationRows(const StateLayout& layout);

// z for every channel from the INS state and the site.
std::array<double, kChannelCount> Observe(const nav::NavState& ins, const Site& site);

}  // namespace insdiag::engine

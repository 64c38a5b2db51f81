// Allan variance of the raw inertial samples over the run's static segments,
// fitted over the whole curve with the noise terms of IEEE Std 952-1997,
// Annex C (gyros) and IEEE Std 1293-1998 (accelerometers: the same terms in
// m/s, m/s²).
//
// Static segments. Sample k covers (t[k−1], t[k]]; it is still when the
// reference attitude at both ends is within `attitude_tolerance_rad` (rotation
// angle) of the attitude at the start of its hold. Holds are split at time
// gaps, lose `motion_guard_s` at each end next to motion, and count when at
// least `min_segment_s` long. A run whose reference never moves is one segment.
//
// Overlapping Allan variance (NIST SP 1065, Riley 2008, eq. 14), per channel,
// with y the rate samples (rad/s or m/s²) and τ₀ the nominal interval:
//   θ_k = τ₀ Σ_{i<k} (y_i − ȳ_s),  k = 0…n_s          per segment s (N_s = n_s + 1 "phase" points)
//   D_m(k) = θ_{k+2m} − 2θ_{k+m} + θ_k,  τ = m τ₀
//   σ̂²(τ) = Σ_s Σ_{k=0}^{M_s−1} D_m(k)² / (2τ² Σ_s M_s),  M_s = N_s − 2m   (segments with M_s ≥ 1)
// Differences never cross segments. m runs on a log grid (`points_per_decade`)
// from 1 to `max_cluster_fraction` of the longest segment.
//
// Confidence intervals: σ̂² ~ σ² χ²_ν/ν with ν = Σ_s ν_s(N_s, m, α), the
// equivalent degrees of freedom of NIST SP 1065 Table 5 (Howe, Allan & Barnes
// 1981; NIST TN 1337 Table 12-4) for the power-law noise S_y ∝ f^α that the
// local slope μ of log σ̂ vs log τ suggests:
//   μ < −¾: phase (angle) noise, α = 2 or 1 — AVAR cannot tell them apart, so
//           the smaller of the two ν (conservative);
//   −¾ ≤ μ < −¼: white rate α = 0;  −¼ ≤ μ < ¼: flicker α = −1;  μ ≥ ¼: random-walk rate α = −2.
//   σ²_low = ν σ̂²/χ²_ν((1+c)/2),  σ²_high = ν σ̂²/χ²_ν((1−c)/2)   (c = `confidence`)
//
// Jumps. The estimator assumes the rate's increments are stationary; a step
// Δ in the mean of a segment's rate (a bias step) is not, and σ̂²(τ) would
// rise by about Δ² τ / (2 T_s) over a segment of T_s: a rate random walk the
// unit does not have, and a white level pulled down to make room for it. With
// the difference of adjacent window means at sample k,
//   d_w(k) = ȳ[k, k+w) − ȳ[k−w, k),   E d_w(k)² = 2 σ²(w τ₀)
// for stationary noise (the Allan variance's own definition; IEEE 952
// Annex C), a step at k shows as d_w(k) ≈ Δ. The largest |d_w(k)| over the
// windows w = 4, 16, 64, … samples that fit `jump_min_windows` times in the
// segment is scaled by s_w, the root mean of d_w² at the samples at least w
// away from it: z = |d_w(k)| / s_w. It is a jump when z exceeds
// Φ⁻¹(1 − α / 2J), J = Σ_w (n − 2w + 1): Bonferroni over every position of
// every window (α = `jump_alpha`; d is Gaussian for Gaussian noise), and
// when it persists: the means over `min_segment_s` either side, beyond w
// samples from k, differ by at least half of d_w(k) with its sign (a
// transient — a spike, a knock on the table, a start-up settling — moves
// d_w near it as a step does, and is not a change of the mean). Over
// n / w positions only it is not a bound: neighbouring d_w(k) decorrelate
// as 1 − 3|h| / 2w, and their maximum exceeds the independent positions'
// (Pickands, Trans. AMS 145, 1969). Each
// channel's segments are cut at their jumps, the pieces tested again (binary
// segmentation: Vostrikova, Soviet Math. Dokl. 24, 1981). A cut needs
// `min_segment_s` and w on either side, so every piece is a segment in
// its own right.
//
// Ramps. A rate that ramps (a bias ramp: a drift that runs away at a steady
// rate) is not noise either, yet over a segment it adds R²τ²/2 to σ²(τ), the
// curve's rate-ramp term, and the drift built from the curve would take it in
// (a ramp's rise looks like a slow drift's). The Hadamard variance
//   σ²_H(τ) = ⅙ E (ȳ_{k+2} − 2ȳ_{k+1} + ȳ_k)²      (NIST SP 1065 §5.2.8)
// takes second differences of adjacent window means, which a linear trend
// leaves at zero. For each noise of the model σ²/σ²_H is at most 2: 0.9 for
// quantisation, 1 for white rate, about 1.23 for flicker, 2 for a rate random
// walk, and from 2 down to 1 for a Markov drift as τ/T grows (from their
// spectra; docs/IDENTIFICATION.md, "Ramps in a static segment"). A channel's
// rise is a ramp when ln(σ̂²/σ̂²_H) stands beyond what a rate random walk, the
// noise of the largest ratio, gives:
//   z_j = (ln(σ̂²_j/σ̂²_H,j) − μ_j) / s_j at each tested point j (those whose
//         τ holds from 8 to 64 windows of the longest piece), z = max_j z_j,
//   μ_j, s_j the mean and standard deviation of the walk's ln ratio there;
//   a ramp when z exceeds the walk's maximum z at level α = `ramp_alpha`.
// A walk is self-similar, so the law depends only on the pieces' lengths
// over m: it is simulated (2000 walks of the pieces at 8 steps to the
// smallest m tested, from a fixed seed), and the bound is the upper tail of
// the walks' maxima, exponential beyond their 95th percentile (peaks over a
// threshold: Pickands, Ann. Stat. 3(1), 1975). The ramp then comes out of
// every piece of the channel: the least-squares fit of
//   y(t) = a + c (t − t₀)₊  over every sample t₀ of the piece that leaves
//   `min_segment_s` after it (t₀ at its start: a line)
// is subtracted, and the curve computed again from what is left.
//
// Noise model (IEEE 952 Annex C, the Markov term as its exponentially correlated noise):
//   σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π) B² + K²τ/3 + R²τ²/2
//         + σ_m² (T/τ)² (2τ/T − 3 + 4e^{−τ/T} − e^{−2τ/T})
//   Q quantisation [rad | m/s], N angle/velocity random walk [rad/√s | m/s/√s],
//   B bias instability [rad/s | m/s²], K rate random walk [rad/s/√s | m/s²/√s],
//   R rate ramp [rad/s² | m/s³], σ_m, T first-order Gauss–Markov drift [rad/s | m/s²], [s]
//   (the engine's base drift model, seed eq. 5–6: R(t) = σ_m² e^{−|t|/T}).
//
// Fit: weighted least squares in log-AVAR with the exact moments of ln χ²_ν,
//   y_j = ln σ̂²_j − [ψ(ν_j/2) − ln(ν_j/2)],  s_j² = ψ′(ν_j/2)       (ψ digamma, ψ′ trigamma)
//   minimise Σ_j ((y_j − ln σ²(τ_j; a)) / s_j)²,  a = ln of each term's AVAR coefficient
// (and ln T), so every term stays non-negative. Starting values: non-negative
// linear least squares of the relative AVAR residuals (all active sets), with
// a grid over T for the Markov term.
//
// Standard errors. AVAR estimates at neighbouring τ share data and are strongly
// correlated, so the fit's own (JᵀWJ)⁻¹ is overconfident. We use the sandwich
//   Cov(â) = (JᵀWJ)⁻¹ JᵀW V W J (JᵀWJ)⁻¹,   W = diag(1/s_j²),  J_jk = ∂ ln σ²(τ_j)/∂a_k,
// with V the covariance of ln σ̂² implied by the fitted model itself: for
// Gaussian noise, Cov(D_i(a)², D_j(b)²) = 2 c_ij(b−a)², and
//   Cov(σ̂²_i, σ̂²_j) = Σ_s 2 Σ_d n_s(d) c_ij(d)² / (4 τ_i² τ_j² M_i M_j),
//   c_ij(d) = Σ_{p,q=0..2} w_p w_q G(τ₀ (d + q m_j − p m_i)),  w = (1, −2, 1),
// where G is the generalised autocovariance of the phase θ (Greenhall, "Estimating
// the Modified Allan Variance", 1995; the functions used in his EDF algorithm):
//   G(h) = Q² [h = 0] − N²|h|/2 + (B²/2π) h² ln|h| + K²|h|³/12 − σ_m² T² (|h|/T − 1 + e^{−|h|/T})
// (the rate ramp is deterministic and adds no variance). V_ij = Cov_ij/(σ²_i σ²_j).
// Lag sums run over the support of the kernels (exact for Q, N, K; the long
// tails of B and the Markov term are cut there) and segments are independent.
//
// Term selection: backward elimination by the Wald statistic z = 1/SE(a_k)
// (= coefficient / its standard error) under the sandwich covariance: the least
// significant term is dropped while z < `significance_z`. Bias instability and
// the Markov term can describe the same flat region (a Markov process looks
// like K for τ ≪ T, like N for τ ≫ T, with a flat top between), and where the
// curve has one flat part neither is resolvable beside the other. Three
// structures are fitted and eliminated: the Markov set {Q, N, K, σ_m/T}, the
// flicker set {Q, N, B, K} and both {Q, N, B, K, σ_m/T} (a drift's bump above
// a floor); of those that keep what makes them differ (σ_m and T; B; all
// three), the one of least AIC = χ²_g under the working V (with δ²) + 2p
// (Akaike, IEEE Trans. Autom. Control 19(6), 1974) is kept, else the flicker
// set as eliminated. The model carries a kept floor as states of its own
// (model/flicker_floor.h). T is bounded so that
// the Markov peak (τ ≈ 1.89 T) lies between 3τ_min and τ_max; on a bound the
// term is unresolved. The rate ramp, deterministic, comes last: it is added
// when its z under the V of the model without it (the null hypothesis) is
// significant — under its own V a ramp claims the large-τ estimates are
// nearly exact and would keep any rise. The working V of the eliminations is
// that of the full Markov candidate fit. `select_terms = false` fits every
// candidate instead.
//
// Adequacy: χ²_g = eᵀV⁻¹e (e the log residuals) against χ² with n − p degrees
// of freedom. When the model cannot explain the curve (p < `adequacy_alpha`:
// dither, motion, temperature), a model-discrepancy variance δ² is added to
// every point (V → V + δ²I, s_j² → s_j² + δ²; δ² solves eᵀ(V + δ²I)⁻¹e = n − p,
// as a random-effects variance), the terms are selected and fitted again with
// these weights — so the most precise short-τ points no longer decide the
// fit alone — and the standard errors include δ. A note names the τ ranges
// that disagree.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"

namespace insdiag::engine::ident {

struct AllanOptions {
  // Still: the reference attitude stays within this rotation angle of the
  // hold's first attitude. About 2″, twice the reading resolution of a
  // precision rate table (≈1″, AnalysisOptions::reference), so encoder jitter
  // does not split a hold while any commanded motion is seen.
  double attitude_tolerance_rad = 1e-5;
  double min_segment_s = 60.0;
  // min_segment_s in samples of τ₀.
  size_t MinSegmentSamples(double tau0_s) const;
  // Dropped at each end of a hold next to motion: the table's settling and
  // the first instants of a ramp, whose attitude change is still below the
  // tolerance.
  double motion_guard_s = 1.0;
  // A step t[k] − t[k−1] above gap_factor · τ₀ ends a segment.
  double gap_factor = 1.5;
  // Family-wise level of the jump test (above) in one segment of one channel.
  double jump_alpha = 1e-3;
  // A window is tested where the segment holds at least this many of it: the
  // scale s_w comes from them, to about ± √(2 / this) in s_w².
  int jump_min_windows = 64;
  // Family-wise level of the ramp test (above) over one channel's curve.
  double ramp_alpha = 1e-3;
  int points_per_decade = 10;
  // Largest cluster: this fraction of the longest segment's samples.
  double max_cluster_fraction = 1.0 / 3.0;
  // Confidence level of the ADEV intervals (0.683: the 1σ convention of NIST SP 1065).
  double confidence = 0.683;
  // Half-width of the window (decades of τ) for the local slope that picks the noise type.
  double slope_window_decades = 0.5;
  // A term stays in the model when coefficient / standard error ≥ this.
  double significance_z = 2.0;
  // The fit is called inadequate when P(χ²_g) is below this.
  double adequacy_alpha = 1e-3;
  // Candidate terms of the fit.
  struct Terms {
    bool quantization = true;
    bool white = true;
    bool bias_instability = true;
    bool rate_random_walk = true;
    bool rate_ramp = true;
    bool markov = true;
  } candidates;
  // false: fit every candidate and report them all (no elimination, no
  // structure choice; bias instability and Markov may then be fitted together).
  bool select_terms = true;
  int max_solver_iterations = 200;

  absl::Status Validate() const;
};

// A span of still samples [first_sample, end_sample) and its time span (t[first] − τ₀, t[end − 1]].
struct StaticSegment {
  size_t first_sample = 0;
  size_t end_sample = 0;
  double start_s = 0.0;
  double end_s = 0.0;

  size_t Samples() const { return end_sample - first_sample; }
};

// Power-law noise S_y(f) ∝ f^α of the rate y (NIST SP 1065 Table 2; for an
// inertial sensor "phase" is the angle / velocity increment).
enum class PowerLawNoise {
  kWhitePhase = 2,      // quantisation
  kFlickerPhase = 1,
  kWhiteRate = 0,       // ARW / VRW
  kFlickerRate = -1,    // bias instability
  kRandomWalkRate = -2, // rate random walk (and, conservatively, ramps)
};

// Equivalent χ² degrees of freedom of the overlapping AVAR of one segment
// with N phase points at cluster size m (NIST SP 1065 Table 5), clamped to
// [1, N − 2m]. 0 when N − 2m < 1.
double AllanEdf(PowerLawNoise noise, int64_t phase_points, int64_t m);

// The noise terms of the model (see the equation above); 0 = absent.
struct AllanNoiseTerms {
  double quantization = 0.0;      // Q [rad | m/s]
  double white_density = 0.0;     // N [rad/√s | m/s/√s]
  double bias_instability = 0.0;  // B [rad/s | m/s²]
  double rate_random_walk = 0.0;  // K [rad/s/√s | m/s²/√s]
  double rate_ramp = 0.0;         // R [rad/s² | m/s³]
  double markov_sigma = 0.0;      // σ_m [rad/s | m/s²]
  double markov_tau_s = 0.0;      // T [s]; the Markov term counts when σ_m > 0 and T > 0
};

// σ²(τ) of the model [(rad/s)² | (m/s²)²].
double ModelAllanVariance(const AllanNoiseTerms& terms, double tau_s);

// Cov(σ̂²(m_i τ₀), σ̂²(m_j τ₀)) of the pooled overlapping estimator under the
// model, for segments of the given sample counts (see above).
double AllanEstimatorCovariance(const AllanNoiseTerms& terms, double tau0_s, int64_t m_i, int64_t m_j,
                                std::span<const size_t> segment_samples);

// The model's parameters, in fit order.
enum class AllanParameter {
  kQuantization,
  kWhiteDensity,
  kBiasInstability,
  kRateRandomWalk,
  kRateRamp,
  kMarkovSigma,
  kMarkovTau,
};
inline constexpr int kAllanParameterCount = 7;
// "Q", "N", "B", "K", "R", "markov_sigma", "markov_tau".
const char* AllanParameterName(AllanParameter p);

struct AllanTermEstimate {
  bool included = false;  // in the selected model
  bool tried = false;     // a candidate of the selected structure
  double value = 0.0;     // in the unit of AllanNoiseTerms
  double std_error = std::numeric_limits<double>::quiet_NaN();  // sandwich, scaled when inadequate
  double z = 0.0;         // coefficient / SE of the AVAR coefficient (1/SE of its log)
};

struct AllanFit {
  std::array<AllanTermEstimate, kAllanParameterCount> parameters;
  bool markov_structure = false;  // σ_m, T fitted (else the flicker set)
  int points = 0;                 // τ points fitted
  int free_parameters = 0;
  double weighted_sse = 0.0;      // Σ ((y − ln σ²)/s)²
  double generalized_chi2 = 0.0;  // eᵀV⁻¹e
  int dof = 0;
  double p_value = 1.0;
  bool adequate = true;
  // δ: the standard deviation of ln σ² the model cannot explain (0 when adequate).
  double discrepancy = 0.0;
  std::vector<std::string> unresolved;  // candidate terms dropped, e.g. "B (z = 0.4)"
  std::vector<std::string> notes;

  const AllanTermEstimate& operator[](AllanParameter p) const { return parameters[static_cast<size_t>(p)]; }
  AllanTermEstimate& operator[](AllanParameter p) { return parameters[static_cast<size_t>(p)]; }
  // The fitted terms (0 for terms not in the model).
  AllanNoiseTerms Terms() const;
};

struct AllanPoint {
  int64_t m = 0;
  double tau_s = 0.0;
  double adev = 0.0;     // σ̂(τ) [rad/s | m/s²]
  double ci_low = 0.0;   // confidence interval of σ(τ)
  double ci_high = 0.0;
  double edf = 0.0;      // ν
  // ν were the noise at τ a rate random walk, the reddest the model holds:
  // the smallest ν, for a bound that must hold whatever the noise there.
  double edf_reddest = 0.0;
  int64_t differences = 0;  // Σ_s M_s
  PowerLawNoise noise = PowerLawNoise::kWhiteRate;  // the type ν was computed for
  double fitted_adev = std::numeric_limits<double>::quiet_NaN();
  double log_residual = std::numeric_limits<double>::quiet_NaN();  // (y − ln σ²_fit)/√V_jj
};

// A jump in the mean of a rate series (above: Jumps).
struct RateJump {
  size_t sample = 0;    // the first sample after the jump, within the series tested
  double size = 0.0;    // d_w there: the later window's mean less the earlier's [rad/s | m/s²]
  double z = 0.0;       // |size| / s_w
  // P(a jump this clear | no jump) over every position of every window
  // tested (J × 2Φ(−z), the bound the test is held to); before any
  // correction over the channels or a segment's pieces.
  double p_value = 1.0;
  int64_t window = 0;   // w, samples
  double time_s = 0.0;  // in the run (AllanAnalysis): the end of the last sample before the jump
};

// The most significant jump in the mean of `rates` (sampled every τ₀), if
// any is significant and persists.
std::optional<RateJump> FindRateJump(std::span<const double> rates, double tau0_s,
                                     const AllanOptions& options);

// The pieces [begin, end) of `rates` between its significant jumps, in
// order; each jump, in order, into `jumps` when given.
struct RatePiece {
  size_t begin = 0;
  size_t end = 0;
};
std::vector<RatePiece> CutAtRateJumps(std::span<const double> rates, double tau0_s,
                                      const AllanOptions& options, std::vector<RateJump>* jumps);

// The evidence that a curve rises as a ramp (above: Ramps), at its most
// significant point.
struct RampEvidence {
  double tau_s = 0.0;
  double avar_over_hvar = 0.0;  // σ̂² / σ̂²_H there
  double z = 0.0;
  // P(the walk's largest z ≥ z) for this channel: the exponential tail
  // beyond the walks' 95th percentile (above).
  double p_value = 1.0;
};

// The point of `curve` where the ramp test is most significant, if it passes;
// `segment_rates` are the pieces the curve was computed from.
std::optional<RampEvidence> RampBeyondNoise(std::span<const std::vector<double>> segment_rates,
                                            std::span<const AllanPoint> curve,
                                            const AllanOptions& options);

// A ramp fitted to one piece of a channel: y(t) = a + c (t − t₀)₊.
struct RateRamp {
  size_t onset_sample = 0;  // t₀'s sample j within the piece: u_k = (k − j)₊ samples
  double onset_s = 0.0;  // t₀: from the piece's first sample; in the run (AllanChannel) its time
  double slope = 0.0;    // c [rad/s² | m/s³]
  double residual_reduction = 0.0;  // Σ y² the ramp removes [(rad/s)² | (m/s²)²]
};

// The least-squares ramp of `rates` (sampled every τ₀) over the onsets that
// leave `min_samples_after` after them; nullopt when the piece is shorter.
std::optional<RateRamp> FitRateRamp(std::span<const double> rates, double tau0_s,
                                    size_t min_samples_after);

struct AllanChannel {
  std::string name;  // "gyro_x", …, "acc_z" (kSensorChannelNames)
  Sensor sensor = Sensor::kGyro;
  int axis = 0;
  std::string unit;  // of adev: "rad/s" | "m/s^2"
  std::vector<RateJump> jumps;  // where its static segments were cut, in time order
  // When the curve rose as a ramp (above: Ramps; `ramp_evidence` says why),
  // every piece loses its ramp; this holds the one that removed the most,
  // the piece that carries the evidence (the others' fits may be their
  // noise's).
  std::vector<RateRamp> ramps;
  std::optional<RampEvidence> ramp_evidence;
  std::vector<AllanPoint> curve;
  AllanFit fit;
  // The output's counting quantum q, where its samples are counts
  // (count_quantum.h).
  std::optional<double> count_quantum;

  // The counter's remainder, q/√12 (count_quantum.h); 0 for an output that
  // is not counted.
  double CountedQuantisation() const;
  // The quantisation coefficient Q of the error model [rad | m/s]: the
  // fit's Q where it resolves one, never below the counter's remainder. The
  // curve's √3 Q/τ branch is any bounded velocity (angle) error — the
  // counter's remainder and the unit's vibration the reference does not
  // record alike — and falls below the remainder only where the input does
  // not move the counter at random (count_quantum.h).
  double Quantisation() const;
  // Whether Quantisation() is the counter's remainder, read rather than fitted.
  bool QuantisationIsCounted() const;
};

struct AllanResult {
  double tau0_s = 0.0;
  std::vector<StaticSegment> segments;
  size_t samples_used = 0;
  std::vector<AllanChannel> channels;  // gyro x, y, z, acc x, y, z
};

// The run's static segments (possibly none long enough: an empty vector).
absl::StatusOr<std::vector<StaticSegment>> FindStaticSegments(const BenchRun& run, const AllanOptions& options);

// Cluster sizes m on the log grid for a longest segment of `longest_samples`.
std::vector<int64_t> AllanClusterSizes(size_t longest_samples, const AllanOptions& options);

// The curve of one channel from its per-segment rate samples: σ̂, ν, CI
// (fitted_adev left NaN).
std::vector<AllanPoint> OverlappingAllanCurve(std::span<const std::vector<double>> segment_rates, double tau0_s,
                                              std::span<const int64_t> cluster_sizes, const AllanOptions& options);

// Fits the noise model to a curve (see above); fills fitted_adev and
// log_residual (e_j/√V_jj, without δ) of `curve`. `segment_samples` are the
// sample counts of the segments the curve pooled (for V). Refuses a curve
// with fewer than two positive points, or no candidate term.
absl::StatusOr<AllanFit> FitAllanCurve(std::vector<AllanPoint>& curve, double tau0_s,
                                       std::span<const size_t> segment_samples, const AllanOptions& options);

// Static segments → per-channel curves → fits. FailedPrecondition when no
// static segment is at least min_segment_s long.
absl::StatusOr<AllanResult> AllanAnalysis(const BenchRun& run, const AllanOptions& options);

// The fitted terms as identified parameters (method "ALLAN"), per channel:
//   {gyro|acc}_quantization.{x,y,z} [rad | m/s]       {gyro_arw|acc_vrw}.{x,y,z} [rad/sqrt(s) | m/s/sqrt(s)]
//   {gyro|acc}_bias_instability.* [rad/s | m/s^2]      {gyro|acc}_rate_random_walk.* [rad/s/sqrt(s) | m/s^2/sqrt(s)]
//     (not named as the catalogue's bias_rw effect: a Markov drift looks the
//     same at τ ≪ its correlation time; correlation processing tells them apart)
//   {gyro|acc}_rate_ramp.* [rad/s^2 | m/s^3]           {gyro|acc}_bias_gm.*.sigma [rad/s | m/s^2], .tau [s]
// Only terms in the selected model are listed. `a_priori`, when given, fills
// ParameterEstimate::a_priori for the names it has.
std::vector<ParameterEstimate> AllanParameterEstimates(const AllanResult& result,
                                                       const ErrorModel* a_priori = nullptr);

// An a-priori base model from the fit, for a run without datasheet values:
//   white noise density ← N; when N is not resolved, the tangent bound min_j σ̂_j √τ_j;
//   quantisation ← AllanChannel::Quantisation(): Q (0 when not resolved), at
//     least a counted output's remainder q/√12;
//   Gauss–Markov drift ← (σ_m, T) when fitted; else from B: the Markov process whose
//     Allan peak (√g* σ_m at τ = u* T, g(u) = (2u − 3 + 4e^{−u} − e^{−2u})/u², maximal at
//     u* ≈ 1.89) equals the flicker floor √(2ln2/π) B at the τ where the fitted curve is
//     lowest; else from K alone: T = the longest τ analysed, σ_m = K √(T/2) (the Markov
//     process with the same short-τ random walk, K² = 2σ_m²/T); else the same
//     construction on the curve's lowest point (an upper bound).
// Notes say which rule each axis took.
absl::StatusOr<ErrorModel> ErrorModelFromAllan(const AllanResult& result, const ReferenceAccuracy& reference,
                                               std::vector<std::string>* notes = nullptr);

// Where the run's Allan deviation lies farthest from what a model predicts
// for one channel: the model's curve from its white noise, quantisation and
// Gauss–Markov drift (ModelAllanVariance; the drift's σ²·g(τ/T) is IEEE 952
// Annex C's first-order Markov term), and at each point of the curve the
// nearer end of its confidence interval (σ̂² ν/χ²_ν, as the curve's own, at
// `family_wise_alpha` over all the curve's points by Bonferroni) over the
// model's deviation. `ratio` is the farthest of those: > 1 when the whole
// interval lies above the model, < 1 below, 1 when every interval holds the
// model's curve.
struct AllanDeparture {
  std::string channel;  // "gyro_x", …, "acc_z"
  double tau_s = 0.0;
  double ratio = 1.0;

  // How far: |ln ratio|, the same above and below.
  double LogDistance() const { return std::abs(std::log(ratio)); }
};
std::vector<AllanDeparture> AllanDeparturesFrom(const AllanResult& result, const ErrorModel& model,
                                                double family_wise_alpha);

}  // namespace insdiag::engine::ident

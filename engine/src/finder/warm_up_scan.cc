#include "insdiag/engine/finder/warm_up_scan.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "insdiag/engine/finder/onset_scan.h"

namespace insdiag::engine {
namespace {

// The warm-up terms in sensor-axis order (SensorAxisIndex).
std::vector<EffectTerm> WarmUpTerms() {
  std::vector<EffectTerm> out;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind == EffectKind::kTransient) out.push_back(term);
  }
  std::sort(out.begin(), out.end(), [](const EffectTerm& a, const EffectTerm& b) {
    return SensorAxisIndex(a.family->sensor, a.axis) < SensorAxisIndex(b.family->sensor, b.axis);
  });
  return out;
}

// The vertex of the parabola through (x_i, y_i), i = 0, 1, 2, clamped to [x_0, x_2].
double ParabolaVertex(double x0, double y0, double x1, double y1, double x2, double y2) {
  const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1);
  const double curvature = (d12 - d01) / (x2 - x0);
  if (!(curvature < 0.0)) return x1;
  return std::clamp(0.5 * (x0 + x1) - d01 / (2.0 * curvature), x0, x2);
}

}  // namespace

std::vector<double> WarmUpTimeConstants(const EpochRun& run, const WarmUpGrid& grid) {
  std::vector<double> out;
  const double shortest_s = grid.shortest_in_update_intervals * run.update_interval_s;
  const double longest_s = grid.longest_share_of_run * run.duration_s;
  for (double tau_s = shortest_s; tau_s <= longest_s && shortest_s > 0.0; tau_s *= grid.ratio) out.push_back(tau_s);
  return out;
}

WarmUpScoreObserver::WarmUpScoreObserver(const StateLayout& layout, const EpochRun& run,
                                         std::vector<double> time_constants_s)
    : time_constants_s_(std::move(time_constants_s)) {
  const auto columns = static_cast<Eigen::Index>(kSensorAxisCount * time_constants_s_.size());
  start_s_ = run.epochs.empty() ? 0.0 : run.epochs.front().start_s;
  sensitivity_.setZero(layout.size(), columns);
  score_.setZero(columns);
  information_.setZero(columns, columns);
  X_.setZero(columns);
}

void WarmUpScoreObserver::OnPrediction(int, const EpochInterval& epoch, const IntervalTransition& t) {
  t.PropagateRows(sensitivity_);
  const double since_start_s = epoch.start_s + 0.5 * epoch.sample_interval_s - start_s_;
  const auto G = static_cast<Eigen::Index>(time_constants_s_.size());
  for (Eigen::Index g = 0; g < G; ++g) {
    const double tau_s = time_constants_s_[static_cast<size_t>(g)];
    const double decay = std::exp(-since_start_s / tau_s);
    if (decay < 1e-12) continue;  // settled: the column adds nothing a double holds beside the rest
    for (int a = 0; a < kSensorAxisCount; ++a) {
      sensitivity_.col(a * G + g).head<kNavigationStates>() +=
          decay * (epoch.moments[0].col(a) - epoch.moments[1].col(a) / tau_s +
                   epoch.moments[2].col(a) / (2.0 * tau_s * tau_s));
    }
  }
}

void WarmUpScoreObserver::OnScalarUpdate(int, const ObservationRow& h, const Eigen::VectorXd& gain,
                                         double innovation, double S) {
  X_ = h.sign * sensitivity_.row(h.state);
  score_.noalias() += X_.transpose() * (innovation / S);
  information_.noalias() += X_.transpose() * (X_ / S);
  sensitivity_.noalias() -= gain * X_;
}

std::vector<WarmUpFit> WarmUpScoreObserver::Fits(const ErrorModel& model) const {
  std::vector<WarmUpFit> out;
  const auto G = static_cast<Eigen::Index>(time_constants_s_.size());
  for (const EffectTerm& term : WarmUpTerms()) {
    if (model.FindEffect(term) >= 0) continue;
    WarmUpFit fit;
    fit.term = term;
    fit.time_constants_tried = static_cast<int>(G);
    const Eigen::Index first = SensorAxisIndex(term.family->sensor, term.axis) * G;
    Eigen::Index best = -1;
    std::vector<double> statistic(static_cast<size_t>(G), 0.0);
    for (Eigen::Index g = 0; g < G; ++g) {
      const double info = information_(first + g, first + g);
      if (!(info > 0.0)) continue;
      statistic[static_cast<size_t>(g)] = score_[first + g] * score_[first + g] / info;
      if (best < 0 || statistic[static_cast<size_t>(g)] > statistic[static_cast<size_t>(best)]) best = g;
      if (g + 1 < G) {
        const double next = information_(first + g + 1, first + g + 1);
        if (next > 0.0) {
          const double rho = information_(first + g, first + g + 1) / std::sqrt(info * next);
          fit.path_length += std::acos(std::clamp(rho, -1.0, 1.0));
        }
      }
    }
    if (best >= 0) {
      const auto b = static_cast<size_t>(best);
      const double info = information_(first + best, first + best);
      fit.identifiable = true;
      fit.statistic = statistic[b];
      fit.estimate = score_[first + best] / info;
      fit.std_error = 1.0 / std::sqrt(info);
      fit.time_constant_s = time_constants_s_[b];
      if (best > 0 && best + 1 < G) {
        fit.time_constant_s = std::exp(ParabolaVertex(
            std::log(time_constants_s_[b - 1]), statistic[b - 1], std::log(time_constants_s_[b]), statistic[b],
            std::log(time_constants_s_[b + 1]), statistic[b + 1]));
      }
      fit.p_value = OnsetPValue(fit.statistic, fit.path_length);
    }
    out.push_back(fit);
  }
  return out;
}

std::vector<EffectCandidate> WarmUpCandidates(const std::vector<WarmUpFit>& fits, int scalar_updates) {
  std::vector<EffectCandidate> out;
  constexpr int kParameters = 2;  // the start value and τ
  for (const WarmUpFit& f : fits) {
    EffectCandidate c;
    c.name = f.term.Name();
    c.family = std::string(f.term.family->name);
    c.source = "SCORE";
    c.unit = std::string(f.term.family->unit);
    c.dof = kParameters;
    c.identifiable = f.identifiable;
    if (!f.identifiable) {
      c.note = "the run carries no information on a bias settling from its start on this axis";
      out.push_back(std::move(c));
      continue;
    }
    c.statistic = f.statistic;
    c.p_value = f.p_value;
    c.estimate = f.estimate;
    c.std_error = f.std_error;
    c.predicted_delta_aic = -f.statistic + 2.0 * kParameters;
    c.predicted_delta_bic = -f.statistic + kParameters * std::log(static_cast<double>(std::max(1, scalar_updates)));
    c.note = "a warm-up settling from the run's start: the score test at its best time constant, τ " +
             std::to_string(static_cast<long>(std::lround(f.time_constant_s))) + " s, of " +
             std::to_string(f.time_constants_tried) + " tried";
    out.push_back(std::move(c));
  }
  return out;
}

absl::StatusOr<std::vector<WarmUpFit>> ScanWarmUps(const EpochRun& run, const ErrorModel& model,
                                                   const WarmUpGrid& grid) {
  std::vector<double> taus = WarmUpTimeConstants(run, grid);
  if (taus.empty()) return std::vector<WarmUpFit>{};
  const StateLayout layout(model);
  WarmUpScoreObserver observer(layout, run, std::move(taus));
  auto forward = RunForwardFilter(run, model, &observer);
  if (!forward.ok()) return forward.status();
  return observer.Fits(model);
}

}  // namespace insdiag::engine

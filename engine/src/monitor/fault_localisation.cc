#include "insdiag/engine/monitor/fault_localisation.h"

#include <algorithm>
#include <cmath>

#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

int EpochAtOrAfter(const ForwardPass& fw, double t) {
  const auto it = std::lower_bound(fw.epoch_time_s.begin(), fw.epoch_time_s.end(), t);
  return static_cast<int>(it - fw.epoch_time_s.begin());
}


}  // namespace

std::vector<JumpHypothesis> LocaliseJump(const ForwardPass& fw, const StateLayout& layout, double flagged_s,
                                         const LocalisationOptions& options) {
  const int K = fw.epochs();
  const int n = fw.state_size;
  const int m = layout.sensor_count();
  const int first = std::max(1, EpochAtOrAfter(fw, flagged_s - options.onset_search_before_s));
  const int last_onset = std::min(K - 1, EpochAtOrAfter(fw, flagged_s + options.onset_search_after_s));
  const int end = std::min(K, EpochAtOrAfter(fw, flagged_s + options.onset_search_after_s + options.window_s) + 1);
  if (first > last_onset || m == 0) return {};

  // The sequential gains of every epoch in the span, rebuilt from P⁻.
  const auto rows = ObservationRows(layout);
  std::vector<Eigen::MatrixXd> gains(static_cast<size_t>(end - first));  // n × channels per epoch
  Eigen::MatrixXd P;
  Eigen::VectorXd PH(n);
  for (int k = first; k < end; ++k) {
    UnpackSymmetric(fw.P_pred.row(k).data(), n, P);
    Eigen::MatrixXd& G = gains[static_cast<size_t>(k - first)];
    G.resize(n, kChannelCount);
    for (int c = 0; c < kChannelCount; ++c) {
      if (!fw.Observed(k, c)) {
        G.col(c).setZero();
        continue;
      }
      const ObservationRow& h = rows[static_cast<size_t>(c)];
      PH = h.sign * P.col(h.state);
      const double S = fw.innovation_variance(k, c);
      G.col(c) = PH / S;
      P.noalias() -= G.col(c) * PH.transpose();
      P.noalias() -= PH * G.col(c).transpose();
      P.noalias() += (S * G.col(c)) * G.col(c).transpose();
    }
  }

  const int window_epochs = std::max(1, EpochAtOrAfter(fw, fw.epoch_time_s[static_cast<size_t>(first)] +
                                                            options.window_s) - first);
  std::vector<JumpHypothesis> best(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) best[static_cast<size_t>(i)].state = layout.sensor_states()[static_cast<size_t>(i)].name;
  int tried = 0;
  Eigen::MatrixXd A(n, m);
  Eigen::VectorXd score(m), information(m), peak(m);
  for (int onset = first; onset <= last_onset; ++onset) {
    ++tried;
    A.setZero();
    for (int i = 0; i < m; ++i) A(layout.sensor_begin() + i, i) = 1.0;
    score.setZero();
    information.setZero();
    peak.setZero();
    const int stop = std::min(end, onset + window_epochs);
    for (int k = onset; k < stop; ++k) {
      if (k > onset) fw.transitions[static_cast<size_t>(k)].PropagateRows(A);
      peak = peak.cwiseMax(A.middleRows<3>(layout.attitude()).colwise().norm().transpose());
      const Eigen::MatrixXd& G = gains[static_cast<size_t>(k - first)];
      for (int c = 0; c < kChannelCount; ++c) {
        if (!fw.Observed(k, c)) continue;
        const ObservationRow& h = rows[static_cast<size_t>(c)];
        const Eigen::RowVectorXd X = h.sign * A.row(h.state);
        const double S = fw.innovation_variance(k, c);
        score += X.transpose() * (fw.innovation(k, c) / S);
        information += X.transpose().cwiseAbs2() / S;
        A.noalias() -= G.col(c) * X;
      }
    }
    for (int i = 0; i < m; ++i) {
      if (!(information[i] > 0.0)) continue;
      const double l = score[i] * score[i] / information[i];
      JumpHypothesis& b = best[static_cast<size_t>(i)];
      if (l > b.statistic) {
        b.statistic = l;
        b.onset_s = fw.epoch_time_s[static_cast<size_t>(onset - 1)];
        b.jump = score[i] / information[i];
        b.jump_std_error = 1.0 / std::sqrt(information[i]);
        b.peak_attitude_error_rad = std::abs(b.jump) * peak[i];
      }
    }
  }
  for (JumpHypothesis& b : best) {
    b.p_value = std::min(1.0, stats::ChiSquareSurvival(b.statistic, 1.0) * tried * m);
  }
  std::sort(best.begin(), best.end(),
            [](const JumpHypothesis& a, const JumpHypothesis& b) { return a.statistic > b.statistic; });
  return best;
}

}  // namespace insdiag::engine

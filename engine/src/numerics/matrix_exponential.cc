#include "insdiag/engine/numerics/matrix_exponential.h"

#include <cmath>

namespace insdiag::engine::numerics {

Eigen::MatrixXd MatrixExponential(const Eigen::MatrixXd& M) {
  // Scale so that ‖M/2^s‖∞ ≤ 1/2, where 20 Taylor terms reach double precision.
  const double norm = M.cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::ceil(std::log2(norm / 0.5)));
  const Eigen::MatrixXd scaled = M / std::ldexp(1.0, squarings);
  const auto n = M.rows();
  Eigen::MatrixXd result = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd term = Eigen::MatrixXd::Identity(n, n);
  constexpr int kTerms = 20;
  for (int k = 1; k <= kTerms; ++k) {
    term = term * scaled / static_cast<double>(k);
    result += term;
  }
  for (int s = 0; s < squarings; ++s) result = result * result;
  return result;
}

ExponentialAndIntegral ExponentialWithIntegral(const Eigen::MatrixXd& F, double t) {
  const auto n = F.rows();
  Eigen::MatrixXd block = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  block.topLeftCorner(n, n) = F * t;
  block.topRightCorner(n, n) = Eigen::MatrixXd::Identity(n, n) * t;
  const Eigen::MatrixXd e = MatrixExponential(block);
  return {e.topLeftCorner(n, n), e.topRightCorner(n, n)};
}

}  // namespace insdiag::engine::numerics

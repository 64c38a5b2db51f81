// e^{F t} and its integral ∫₀ᵗ e^{F s} ds for a small dense F, by the block
// exponential (Van Loan, "Computing integrals involving the matrix
// exponential", IEEE Trans. Automatic Control 23(3), 1978):
//
//   exp([F I; 0 0] t) = [e^{Ft}  ∫₀ᵗ e^{Fs} ds; 0 I]
//
// evaluated by scaling and squaring with a Taylor series (Moler & Van Loan,
// "Nineteen dubious ways to compute the exponential of a matrix", 2003, §3).
#pragma once

#include <Eigen/Core>

namespace insdiag::engine::numerics {

struct ExponentialAndIntegral {
  Eigen::MatrixXd exponential;  // e^{F t}
  Eigen::MatrixXd integral;     // ∫₀ᵗ e^{F s} ds
};

Eigen::MatrixXd MatrixExponential(const Eigen::MatrixXd& M);
ExponentialAndIntegral ExponentialWithIntegral(const Eigen::MatrixXd& F, double t);

}  // namespace insdiag::engine::numerics

// Rauch-Tung-Striebel fixed-interval smoother for an error-state Kalman filter WITH
// FEEDBACK (problem-agnostic). The filter stores a "knot" at chosen epochs: the transition
// from the previous knot, the covariance before and after the updates of that epoch, and
// the total correction it fed back into its nominal state there.
//
// With feedback, the filter's error estimate after each knot's updates is zero relative
// to the post-update nominal x_k^+; relative to the pre-update nominal x_k^- it is
// dx_fed_back_k. The prior error at knot k+1 relative to x_{k+1}^+ is therefore
// -dx_fed_back_{k+1}, and the smoothed error relative to x_{k+1}^- is
// dx^s_{k+1} + dx_fed_back_{k+1}. The standard RTS gain A_k then gives the smoothed
// error relative to x_k^+ (Rauch, Tung, Striebel, AIAA J. 3(8), 1965; with feedback e.g.
// Groves 2013, sec. 3.4.2 adapted to the feedback form):
//   dx^s_N = 0, P^s_N = P_post_N; for k = N-1 .. 0:
//     A_k     = P_post_k Phi_{k+1}^T (P_prior_{k+1})^-1
//     dx^s_k  = A_k (dx^s_{k+1} + dx_fed_back_{k+1})
//     P^s_k   = P_post_k + A_k (P^s_{k+1} - P_prior_{k+1}) A_k^T   (symmetrised)
// The smoothed state is x_k^+ (+) dx^s_k.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace navtwin {

/// One stored epoch ("knot") of an error-state filter with feedback.
struct RtsKnot {
  Eigen::MatrixXd Phi;      ///< transition from the previous knot to this one (ignored for knot 0)
  Eigen::MatrixXd P_prior;  ///< covariance at this knot before its updates (= P_post if none)
  Eigen::MatrixXd P_post;   ///< after its updates
  Eigen::VectorXd dx_fed_back;  ///< sum of the corrections fed back at this knot (zero if none;
                                ///< an empty vector is read as zero)
};

struct RtsResult {
  std::vector<Eigen::VectorXd> dx;  ///< smoothed error at each knot, relative to the POST-update nominal
  std::vector<Eigen::MatrixXd> P;   ///< smoothed covariance
};

/// Backward pass (see the header comment). P_prior_{k+1} is inverted through its LDLT
/// (robust to a semi-definite prior on states the filter never excites). Throws
/// std::invalid_argument on inconsistent sizes. An empty input gives an empty result.
RtsResult RunRts(const std::vector<RtsKnot>& knots);

}  // namespace navtwin

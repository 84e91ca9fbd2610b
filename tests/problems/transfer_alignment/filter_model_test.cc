// The transfer filters' shared model (problems/transfer_alignment/filter_model.h): the
// instrument-error columns of the error dynamics against the strapdown itself.
#include "problems/transfer_alignment/filter_model.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/imu_error_model.h"
#include "core/rotation.h"
#include "core/strapdown.h"

namespace navtwin::transfer {
namespace transfer_filter_model_test {

/// One strapdown step from `start` with the sample measured by a triad with instrument
/// errors e (istate layout: per triad K = I + diag(s) + M and the bias b, x_m = K x + b dt);
/// returns the error (true minus estimate) [dv, phi] after it,
/// the truth being the same step with the exact sample.
Eigen::Matrix<double, 6, 1> StepError(const NavState& start, const ImuSample& exact,
                                      const Eigen::Matrix<double, kInstrumentStates, 1>& e) {
  ImuSample measured = exact;
  measured.dtheta_b_rad =
      TriadMatrix(e.data() + istate::kSg) * exact.dtheta_b_rad + TriadBias(e.data() + istate::kSg) * exact.dt_s;
  measured.dv_b_mps = TriadMatrix(e.data() + istate::kSa) * exact.dv_b_mps + TriadBias(e.data() + istate::kSa) * exact.dt_s;
  Strapdown truth(start), estimate(start);
  truth.Update(exact);
  estimate.Update(measured);
  Eigen::Matrix<double, 6, 1> d;
  d.head<3>() = truth.state().v_n_mps - estimate.state().v_n_mps;
  d.tail<3>() = LogSO3<double>(Eigen::Matrix3d(truth.state().q_n_b.toRotationMatrix() *
                                               estimate.state().q_n_b.toRotationMatrix().transpose()));
  return d;
}

// Over one 10 ms step from zero error, dx = Phi_xi e with Phi_xi = F_xi dt + F_xx F_xi dt^2 / 2
// (the history filter's transition): central differences of the strapdown's error in each
// instrument error (step 1e-4, linear to 1e-8) match it to the step's third-order terms and
// the strapdown's own within-step coning and sculling, about 0.5 % of the column at
// 0.5 rad/s (tolerance 1 %, plus 1e-12 for the rounding of 1e-16 / 1e-4).
TEST(TransferFilterModel, InstrumentColumnsMatchTheStrapdown) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    NavState start;
    start.t_s = 100.0;
    start.lat_rad = 0.6 + 0.1 * trial;
    start.lon_rad = 2.2;
    start.h_m = 3000.0;
    start.v_n_mps = Eigen::Vector3d(200.0, -20.0, 5.0);
    start.q_n_b = Eigen::Quaterniond(ExpSO3<double>(Eigen::Vector3d(n(rng), n(rng), n(rng)))).normalized();
    ImuSample exact;
    exact.dt_s = 0.01;
    exact.t_s = start.t_s + exact.dt_s;
    exact.dtheta_b_rad = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.5 * exact.dt_s;  // ~0.5 rad/s
    exact.dv_b_mps = (Eigen::Vector3d(0.0, 0.0, -9.8) + 20.0 * Eigen::Vector3d(n(rng), n(rng), n(rng))) * exact.dt_s;
    TransferMatrix F;
    InstrumentColumns Fi;
    TransferErrorDynamics(start, exact, &F, &Fi);
    const double h = 1e-4;
    for (int k = 0; k < kInstrumentStates; ++k) {
      const Eigen::Matrix<double, kInstrumentStates, 1> d = h * Eigen::Matrix<double, kInstrumentStates, 1>::Unit(k);
      const Eigen::Matrix<double, 6, 1> numeric = (StepError(start, exact, d) - StepError(start, exact, -d)) / (2 * h);
      const double dt = exact.dt_s;
      const Eigen::Matrix<double, 6, 1> analytic = (Fi.col(k) * dt + 0.5 * F * Fi.col(k) * dt * dt).head<6>();
      EXPECT_LT((analytic - numeric).norm(), 0.01 * numeric.norm() + 1e-12)
          << "trial " << trial << " column " << k << "\nanalytic " << analytic.transpose() << "\nnumeric  "
          << numeric.transpose();
      EXPECT_TRUE(Fi.col(k).tail<4>().isZero(0.0));  // mu and tau do not feel them
    }
  }
}

}  // namespace transfer_filter_model_test
}  // namespace navtwin::transfer

#include "problems/transfer_alignment/monte_carlo.h"

#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>

#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::transfer {

namespace {

constexpr double kMsPerS = 1.0 / kMillisecond_s;  // display scales
constexpr double kMradPerRad = 1.0 / kMrad_rad;

/// Whole seconds after the slave's start up to its last IMU sample.
std::vector<double> McGrid(const TransferInputs& in) {
  return mc::WholeSecondGrid(in.slave_initial.t_s, in.slave_imu.back().t_s);
}

/// Log(M_est M_true^T), M = R_b_s from ZYX Euler angles in degrees: the misalignment error
/// as a rotation vector in the master body axes (rad), estimate minus truth.
Eigen::Vector3d MisalignmentError(const Eigen::Vector3d& rpy_est_deg, const Eigen::Quaterniond& M_true) {
  const Eigen::Vector3d r = rpy_est_deg * kDegToRad;
  return AttitudeError(QuatFromEuler(r.x(), r.y(), r.z()), M_true);
}

mc::Quantity MisalignmentQuantity(const std::vector<double>& grid) {
  return mc::Quantity::Empty("misalignment", "mrad", kMradPerRad, "t_s", {"x", "y", "z"}, grid);
}
mc::Quantity DelayQuantity(const std::vector<double>& grid) {
  return mc::Quantity::Empty("delay", "ms", kMsPerS, "t_s", {"tau"}, grid);
}
mc::Quantity JointQuantity(double t_final) {
  return mc::Quantity::Empty("misalignment_delay", "rad|s", 1.0, "t_s", {"x", "y", "z", "tau"}, {t_final});
}

/// The final joint error and covariance of a result (misalignment, delay).
void SetFinalJoint(const TransferResult& r, const TransferInputs& in, mc::Quantity* joint, mc::Quantity* mis,
                   mc::Quantity* delay) {
  Eigen::Vector4d e;
  e.head<3>() = MisalignmentError(r.misalignment_deg, *in.true_misalignment);
  e(3) = r.delay_s - *in.true_delay_s;
  const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> P = r.misalignment_delay_covariance;
  joint->Set(0, e.data(), P.data());
  const int last = mis->points() - 1;
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> Pm = P.topLeftCorner<3, 3>();
  mis->Set(last, e.data(), Pm.data());
  const double var_tau = P(3, 3);
  delay->Set(last, &e(3), &var_tau);
}

/// The method's quantities on the grid from its estimates (latest at or before each point).
std::vector<mc::Quantity> QuantitiesOf(const TransferResult& r, const TransferInputs& in,
                                       const std::vector<double>& grid) {
  mc::Quantity mis = MisalignmentQuantity(grid), delay = DelayQuantity(grid);
  mc::Quantity attitude = mc::Quantity::Empty("attitude", "mrad", kMradPerRad, "t_s", {"roll", "pitch", "heading"}, grid);
  std::size_t k = 0, a = 0;
  for (int p = 0; p < static_cast<int>(grid.size()); ++p) {
    while (k < r.estimates.size() && r.estimates[k].t_s <= grid[p]) ++k;
    if (k > 0) {
      const TransferResult::Estimate& est = r.estimates[k - 1];
      const Eigen::Vector3d e = MisalignmentError(est.misalignment_deg, *in.true_misalignment);
      const Eigen::Vector3d sigma = est.misalignment_sigma_mrad / kMradPerRad;
      mis.SetDiagonal(p, e.data(), sigma.data());
      const double e_tau = est.delay_s - *in.true_delay_s;
      delay.SetDiagonal(p, &e_tau, &est.delay_sigma_s);
    }
    while (a < r.t_s.size() && r.t_s[a] <= grid[p]) ++a;
    if (a > 0) {
      const Eigen::Vector3d e = r.error_mrad[a - 1] / kMradPerRad;
      const Eigen::Matrix3d unknown = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
      attitude.Set(p, e.data(), unknown.data());
    }
  }
  mc::Quantity joint = JointQuantity(grid.back());
  SetFinalJoint(r, in, &joint, &mis, &delay);
  return {mis, delay, joint, attitude};
}

}  // namespace

mc::RunRecord TransferMcRun(const sim::Scenario& scenario, const TransferConfig& config,
                            const std::vector<Method>& methods, std::uint64_t seed, int run) {
  mc::RunRecord record;
  record.run = run;
  record.seed = seed;
  const TransferInputs inputs = SimulateTransferInputs(scenario, seed);
  const std::vector<double> grid = McGrid(inputs);
  for (const Method m : methods) {
    mc::MethodRecord mr;
    mr.method = MethodName(m);
    try {
      const TransferResult r = RunMethod(inputs, config, m);
      mr.run_time_s = r.run_time_s;
      mr.quantities = QuantitiesOf(r, inputs, grid);
    } catch (const std::exception& e) {
      mr.failure = e.what();
      mr.quantities.clear();
    }
    record.methods.push_back(std::move(mr));
  }
  return record;
}

mc::MethodRecord TransferBound(const sim::Scenario& scenario, const TransferConfig& config, std::uint64_t seed) {
  const TransferInputs inputs = SimulateTransferInputs(scenario, seed, std::nullopt, /*perfect=*/true);
  const std::vector<double> grid = McGrid(inputs);
  const TransferResult r = RunMethod(inputs, config, Method::kBatch);
  mc::MethodRecord bound;
  bound.method = "bound";
  bound.run_time_s = r.run_time_s;
  mc::Quantity mis = MisalignmentQuantity({grid.back()}), delay = DelayQuantity({grid.back()});
  mc::Quantity joint = JointQuantity(grid.back());
  SetFinalJoint(r, inputs, &joint, &mis, &delay);
  bound.quantities = {mis, delay, joint};
  return bound;
}

}  // namespace navtwin::transfer

// What the transfer-alignment filters share (filter.h: the seed's order-1 and order-2
// forms; history_filter.h: delayed-state fusion): the 10-state error model, its
// propagation, the initial covariance and process noise from the configuration, the
// slave position reset from the master, and the walk over the slave IMU that stops at
// every master record's tag.
//
// Error state (true minus estimate):
//   [0,3) dv_n_mps   slave velocity,  v_true = v + dv
//   [3,6) phi_n_rad  slave attitude,  R_n_s_true = Exp(phi) R_n_s (core/rotation.h)
//   [6,9) mu_b_rad   misalignment,    R_b_s_true = Exp(mu) R_b_s (master body axes)
//   [9]   dtau_s     delay,           tau_true = tau + dtau
// dv and phi follow the INS error model of problems/ins/error_dynamics.h (its velocity and
// attitude rows and columns; the position errors are left out because the position is
// reset from the master at every record); mu and dtau are random constants with small
// random walks. Process noise per state (continuous PSD): q_v = VRW^2 + sigma_ba^2 T_b,
// q_phi = ARW^2 + sigma_bg^2 T_b in the order filters, where the slave biases are not
// states and are covered by white noise whose variance grows like the bias's effect over
// the filter's memory T_b: sigma_b^2 T_b^2 = q T_b. The history filter carries the biases
// (with the other instrument errors, istate below) and has only VRW^2 and ARW^2.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "core/imu_error_model.h"
#include "core/types.h"
#include "problems/ins/error_dynamics.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/inputs.h"
#include "problems/transfer_alignment/master.h"

namespace navtwin::transfer {

constexpr int kTransferStates = 10;
using TransferMatrix = Eigen::Matrix<double, kTransferStates, kTransferStates>;
using TransferVector = Eigen::Matrix<double, kTransferStates, 1>;

/// Offsets of the error-state blocks.
namespace tstate {
constexpr int kVel = 0;
constexpr int kAtt = 3;
constexpr int kMis = 6;
constexpr int kTau = 9;
}  // namespace tstate

/// Throws std::invalid_argument ("<who>: configuration: ...") for a setting a filter
/// cannot run with (negative noise, zero initial sigma, ...).
void CheckTransferFilterConfig(const TransferConfig& config, const char* who);

/// Records in the master-derivative fit window (config.h master_fit_window_s): the window
/// over the median record spacing, at least 3; 0 (differences) for a zero window.
int MasterFitRecords(const std::vector<NavState>& master, double window_s);

/// sqrt diag of the initial covariance: initial_velocity, initial_attitude, misalignment, delay.
TransferVector TransferInitialSigma(const TransferConfig& config);

/// How a filter treats the slave's gyro and accelerometer biases: as white process noise
/// over a memory of seconds (the order filters, header comment), or as states (the history
/// filter: istate::kBg, istate::kBa), when they add no process noise.
enum class SlaveBiases { kAsNoise, kAsStates };

/// Continuous process-noise PSD per state (header comment).
TransferVector TransferProcessNoise(const TransferConfig& config, SlaveBiases biases);

/// The slave triads' instrument errors as filter states (history_filter.h): per triad its
/// scale factors s (3), axis misalignments M (6) and bias b (3), exactly core/imu_error_model.h's
/// triad block (so TriadMatrix and TriadBias read them), gyro then accelerometer; random
/// constants.
constexpr int kInstrumentStates = 2 * kTriadParameters;
using InstrumentColumns = Eigen::Matrix<double, kTransferStates, kInstrumentStates>;
namespace istate {
constexpr int kSg = 0;                      ///< gyro triad: scale factors, then
constexpr int kMg = 3;                      ///< its misalignments, then
constexpr int kBg = 9;                      ///< its bias (rad/s)
constexpr int kSa = kTriadParameters;       ///< accelerometer triad: scale factors, then
constexpr int kMa = kTriadParameters + 3;   ///< its misalignments, then
constexpr int kBa = kTriadParameters + 9;   ///< its bias (m/s^2)
}  // namespace istate

using InstrumentPrior = Eigen::Matrix<double, kInstrumentStates, 1>;

/// The prior sigma of each instrument error (istate layout) from the configuration's
/// gyro/accel scale-factor, axis-misalignment and bias sigmas.
InstrumentPrior InstrumentPriorSigma(const TransferConfig& config);

/// F as below and d(dx_dot)/d(instrument errors) (10 x 24): the biases' columns are F's
/// gyro- and accelerometer-bias columns (ins::ErrorDynamicsF); a gyro error matrix E_g acts
/// as a bias E_g omega, so its columns are the gyro-bias columns times diag(omega) (sg) and
/// MisalignmentColumns(omega) (mg); the accelerometer's likewise with f. omega and f from
/// the sample (already corrected for the current estimates).
void TransferErrorDynamics(const NavState& nav, const ImuSample& s, TransferMatrix* F,
                           InstrumentColumns* F_instrument);

/// Transition over one IMU sample s from the nominal slave state nav (at the sample's
/// start): Phi = I + F dt + (F dt)^2 / 2 with F the dv/phi block of ins::ErrorDynamicsF
/// (zero elsewhere); with phi_instrument, also the instrument errors' columns of the same
/// second-order transition, Phi_xi = F_xi dt + F F_xi dt^2 / 2 (their own block is I).
TransferMatrix TransferTransition(const NavState& nav, const ImuSample& s,
                                  InstrumentColumns* phi_instrument = nullptr);

/// The slave position set from the master record carried forward over tau with its
/// velocity (local NED offset v tau on the ellipsoid's radii; metres of error at most,
/// which the velocity dynamics barely feel).
void ResetSlavePosition(const NavState& record, double tau_s, NavState* slave);

/// Throws std::runtime_error "<who>: <what> became non-finite at t = <t_s> s".
[[noreturn]] void ThrowNonFinite(const char* who, double t_s, const char* what);

/// Walks the slave IMU from t0_s: calls propagate(sample) for each sample (or the part of
/// one up to a master tag inside it) and update(k) for each master record k whose tag lies
/// in [t0_s, last slave sample], after the slave has been stepped to the tag.
void WalkSlaveImu(const std::vector<ImuSample>& slave_imu, const MasterStream& master, double t0_s,
                  const std::function<void(const ImuSample&)>& propagate,
                  const std::function<void(std::size_t)>& update);

}  // namespace navtwin::transfer

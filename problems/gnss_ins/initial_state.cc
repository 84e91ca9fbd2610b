// The initial state of the GNSS/INS estimators per InitConfig::Source (the static
// alignment's heading by a search in heading_search.cc) and its standard deviations.
#include "problems/gnss_ins/initial_state.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "problems/ins/alignment.h"
#include "problems/ins/error_dynamics.h"
#include "problems/gnss_ins/heading_search.h"
#include "problems/ins/sources/mag.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {
namespace {

std::string Seconds(double t_s) {
  std::ostringstream s;
  s.precision(12);
  s << t_s << " s";
  return s.str();
}

/// Zero entries of `given` replaced by `fallback`.
Eigen::Vector3d OrDefault(const Eigen::Vector3d& given, double fallback) {
  Eigen::Vector3d out = given;
  for (int i = 0; i < 3; ++i) {
    if (out[i] == 0.0) out[i] = fallback;
  }
  return out;
}

bool AnyNonZero(const ImuErrors& e) {
  return !e.bg_radps.isZero(0.0) || !e.ba_mps2.isZero(0.0) || !e.sg.isZero(0.0) || !e.sa.isZero(0.0);
}

/// The position and the start from the first GNSS fix at or after the start (which made
/// the state: its measurements are skipped).
void PositionFromFirstFix(const Inputs& inputs, const GnssInsConfig& config, FilterStart* start) {
  NavState& nav = start->state.nav;
  const auto fix = std::find_if(inputs.gnss.begin(), inputs.gnss.end(), [&](const GnssSample& g) {
    return g.t_s >= nav.t_s - ins::kSameEpoch_s && g.t_s < inputs.imu.known_end_s();
  });
  if (fix == inputs.gnss.end()) {
    throw InputError(inputs.paths.gnss, 0, "position",
                     "the initial position comes from the first GNSS fix at or after " + Seconds(nav.t_s) +
                         ", and the IMU record has none after it");
  }
  ins::ImuPositionFromAntenna(*fix, nav.q_n_b, config.installation.antenna_lever_arm_b_m, &nav);
  nav.t_s = fix->t_s;
  nav.gps_week = fix->gps_week;
  start->use_measurements_at_start = false;
}

FilterStart GivenStart(const Inputs& inputs, const GnssInsConfig& config) {
  if (!config.init.state) {
    throw std::invalid_argument("RunFilter: init.source given needs init.state");
  }
  FilterStart start;
  start.state = *config.init.state;
  if (AnyNonZero(config.init.imu_errors)) start.state.imu = config.init.imu_errors;
  const double imu_begin_s = inputs.imu.begin_s();
  // A start before the IMU record is taken at its beginning (as KF-GINS does with a
  // starttime before the first IMU sample).
  if (start.state.nav.t_s < imu_begin_s) start.state.nav.t_s = imu_begin_s;
  start.use_measurements_at_start = true;
  if (config.init.position_from_gnss) PositionFromFirstFix(inputs, config, &start);
  return start;
}

FilterStart StaticAlignmentStart(const Inputs& inputs, const GnssInsConfig& config, std::ostream* progress) {
  const InitConfig& init = config.init;
  const double begin_s = inputs.imu.begin_s();
  const double end_s = begin_s + init.static_duration_s;
  std::vector<ImuSample> samples;
  for (const ImuSample& s : inputs.imu.Head(end_s + ins::kSameEpoch_s)) {
    if (s.t_s > end_s + ins::kSameEpoch_s) break;
    samples.push_back(CorrectImu(s, init.imu_errors));
  }
  if (inputs.gnss.empty()) {
    throw InputError(inputs.paths.gnss, 0, "position",
                     "static alignment takes the position from the first GNSS fix, and the GNSS "
                     "record is empty");
  }
  const GnssSample& fix = inputs.gnss.front();
  // The heading reference: the magnetometer (kMagnetometer, or kAuto with one), else the
  // mean angular rate (gyrocompassing; for kSearch only roll and pitch are kept).
  const InitConfig::Heading heading = init.heading;
  const bool mag_on = config.mag.mode != MagConfig::Mode::kOff;
  if (heading == InitConfig::Heading::kMagnetometer && !mag_on) {
    throw std::invalid_argument("RunFilter: init.heading magnetometer needs mag.mode other than off");
  }
  std::optional<Eigen::Vector3d> m_b_uT;
  if (heading == InitConfig::Heading::kMagnetometer || (heading == InitConfig::Heading::kAuto && mag_on)) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (const MagSample& m : inputs.mag) {
      if (m.t_s < begin_s - ins::kSameEpoch_s) continue;
      if (m.t_s > samples.back().t_s + ins::kSameEpoch_s) break;
      sum += CalibrateMag(m.m_b_uT, config.mag);
      ++count;
    }
    if (count > 0) m_b_uT = sum / count;
    if (count == 0 && heading == InitConfig::Heading::kMagnetometer) {
      throw InputError(inputs.paths.mag, 0, "heading",
                       "no magnetometer sample in the static alignment window (the first " +
                           Seconds(init.static_duration_s) + " of IMU data)");
    }
  }
  FilterStart start;
  start.state.imu = init.imu_errors;
  NavState& nav = start.state.nav;
  try {
    nav.q_n_b = ins::StaticCoarseAlignment(samples, fix.lat_rad, m_b_uT, config.mag.declination_rad);
  } catch (const std::invalid_argument& e) {
    throw InputError(inputs.paths.imu, 0, "static alignment",
                     std::string(e.what()) + " (the first " + Seconds(init.static_duration_s) +
                         " of IMU data)");
  }
  ins::ImuPositionFromAntenna(fix, nav.q_n_b, config.installation.antenna_lever_arm_b_m, &nav);
  nav.v_n_mps.setZero();
  nav.t_s = samples.back().t_s;
  nav.gps_week = fix.gps_week;
  start.use_measurements_at_start = false;
  if (heading == InitConfig::Heading::kSearch) {
    // Roll and pitch from the alignment, the heading from the search; the IMU position
    // follows the heading through the lever arm.
    const Eigen::Vector3d rpy = EulerFromQuat<double>(nav.q_n_b);
    const InsState levelled = start.state;
    const auto state_for_yaw = [&](double yaw_rad) {
      InsState s = levelled;
      s.nav.q_n_b = QuatFromEuler<double>(rpy[0], rpy[1], yaw_rad);
      ins::ImuPositionFromAntenna(fix, s.nav.q_n_b, config.installation.antenna_lever_arm_b_m, &s.nav);
      return s;
    };
    const HeadingSearchResult search = SearchHeading(inputs, config, state_for_yaw, progress);
    start.state = state_for_yaw(search.hypotheses[search.best].yaw_rad);
  }
  return start;
}

FilterStart GnssVelocityStart(const Inputs& inputs, const GnssInsConfig& config) {
  const double imu_begin_s = inputs.imu.begin_s();
  const double imu_end_s = inputs.imu.known_end_s();  // +infinity before a streamed record's first pass
  for (const GnssSample& fix : inputs.gnss) {
    if (fix.t_s < imu_begin_s || fix.t_s >= imu_end_s) continue;
    if (!fix.has_velocity || fix.v_n_mps.head<2>().norm() < config.init.min_speed_mps) continue;
    FilterStart start;
    start.state.imu = config.init.imu_errors;
    NavState& nav = start.state.nav;
    nav.q_n_b = ins::AttitudeFromGnssVelocity(fix.v_n_mps);
    ins::ImuPositionFromAntenna(fix, nav.q_n_b, config.installation.antenna_lever_arm_b_m, &nav);
    nav.v_n_mps = fix.v_n_mps;
    nav.t_s = fix.t_s;
    nav.gps_week = fix.gps_week;
    start.use_measurements_at_start = false;  // the fix at the start made the state
    return start;
  }
  std::ostringstream reason;
  reason << "no GNSS fix with velocity and a horizontal speed of at least " << config.init.min_speed_mps
         << " m/s inside the IMU record: cannot take the heading from the GNSS velocity";
  throw InputError(inputs.paths.gnss, 0, "velocity", reason.str());
}

}  // namespace

Eigen::VectorXd InitialStdVector(const GnssInsConfig& config, int n) {
  if (n != err::kSize15 && n != err::kSize21) {
    throw std::invalid_argument("InitialStdVector: n must be 15 or 21");
  }
  const InitialStd& s = config.init.std;
  const ImuNoise& noise = config.imu_noise;
  Eigen::VectorXd std(n);
  std.segment<3>(err::kPos) = s.pos_ned_m;
  std.segment<3>(err::kVel) = s.vel_ned_mps;
  std.segment<3>(err::kAtt) = s.att_rad;
  if (config.init.source == InitConfig::Source::kStaticAlignment &&
      config.init.heading == InitConfig::Heading::kSearch) {
    std[err::kAtt + 2] = HeadingSearchYawStd(config.init.heading_hypotheses);
  }
  std.segment<3>(err::kBg) = OrDefault(s.bg_radps, noise.gyro_bias_std_radps);
  std.segment<3>(err::kBa) = OrDefault(s.ba_mps2, noise.accel_bias_std_mps2);
  if (n == err::kSize21) {
    std.segment<3>(err::kSg) = OrDefault(s.sg, noise.gyro_scale_std);
    std.segment<3>(err::kSa) = OrDefault(s.sa, noise.accel_scale_std);
  }
  if (!std.allFinite() || (std.array() < 0.0).any()) {
    throw std::invalid_argument("InitialStdVector: initial standard deviations must be finite and >= 0");
  }
  return std;
}

FilterStart InitialFilterState(const Inputs& inputs, const GnssInsConfig& config, std::ostream* progress) {
  if (inputs.imu.empty()) throw InputError(inputs.paths.imu, 0, "", "no IMU samples");
  FilterStart start;
  switch (config.init.source) {
    case InitConfig::Source::kGiven:
      start = GivenStart(inputs, config);
      break;
    case InitConfig::Source::kStaticAlignment:
      start = StaticAlignmentStart(inputs, config, progress);
      break;
    case InitConfig::Source::kGnssVelocity:
      start = GnssVelocityStart(inputs, config);
      break;
    default:
      throw std::invalid_argument("RunFilter: unknown init.source");
  }
  start.std = InitialStdVector(config, config.filter.scale_factors ? err::kSize21 : err::kSize15);
  return start;
}

}  // namespace navtwin::gnss_ins

#include "problems/gnss_ins/sim_config.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "core/config/yaml_config.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::gnss_ins {
namespace {


std::string Num(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

std::string Vec(const Eigen::Vector3d& v, double scale = 1.0) {
  return "[" + Num(v.x() * scale) + ", " + Num(v.y() * scale) + ", " + Num(v.z() * scale) + "]";
}

Eigen::Vector3d VecFrom(const YAML::Node& n, const std::string& what) {
  if (!n || !n.IsSequence() || n.size() != 3) {
    throw std::runtime_error("errors.yaml: " + what + " is not a 3-vector");
  }
  return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

/// The filter estimates the scale factors when the scenario draws any.
bool EstimatesScaleFactors(const sim::TriadErrorConfig& gyro, const sim::TriadErrorConfig& accel) {
  return gyro.scale_factor.sigma > 0.0 || accel.scale_factor.sigma > 0.0;
}

/// The scale-factor priors; a triad without scale-factor errors next to one with them gets
/// 1 ppm (the configuration needs a positive sigma), none when neither has any.
std::string ScaleFactorLines(const sim::TriadErrorConfig& gyro, const sim::TriadErrorConfig& accel) {
  if (!EstimatesScaleFactors(gyro, accel)) return "";
  const auto ppm = [](const sim::TriadErrorConfig& t) { return std::max(t.scale_factor.sigma / kPpm, 1.0); };
  return "  gyro_scale_std_ppm: " + Num(ppm(gyro)) + "\n  accel_scale_std_ppm: " + Num(ppm(accel)) + "\n";
}

}  // namespace

std::string ConfigYamlForSimulation(const sim::Scenario& scenario, const std::string& sim_dir,
                                    std::uint64_t seed, const std::string& mag_mode) {
  if (mag_mode != "off" && mag_mode != "vector" && mag_mode != "heading" && mag_mode != "heading_2axis") {
    throw std::invalid_argument("magnetometer mode '" + mag_mode + "': expected off, vector, heading or heading_2axis");
  }
  if (!scenario.gnss) throw std::invalid_argument("scenario " + scenario.name + " has no GNSS");
  if (mag_mode != "off" && !scenario.mag) {
    throw std::invalid_argument("scenario " + scenario.name + " has no magnetometer (use mode off)");
  }
  const sim::TriadErrorConfig& gyro = scenario.imu.errors.gyro;
  const sim::TriadErrorConfig& accel = scenario.imu.errors.accel;
  std::ostringstream y;
  y << "# navtwin configuration for the simulated " << scenario.name << " (seed " << seed << "):\n"
       "# the scenario's IMU noise, installation and initial state (init.nav)"
    << (mag_mode != "off" ? ", and the magnetometer\n# calibration and field from errors.yaml, as a user "
                            "with a calibrated magnetometer would have them.\n"
                          : ".\n")
    << "imu_noise:\n"
       "  gyro_arw_deg_sqrt_h: " << Num(gyro.white_noise / kDegPerSqrtHour_radpsqrts) << "\n"
       "  accel_vrw_m_s_sqrt_h: " << Num(accel.white_noise / kMpsPerSqrtHour_mpspsqrts) << "\n"
       "  gyro_bias_std_deg_h: " << Num(gyro.bias.sigma / kDegPerHour_radps) << "\n"
       "  accel_bias_std_ug: " << Num(accel.bias.sigma / kMicroG_mps2) << "\n"
    << ScaleFactorLines(gyro, accel)
    << "  correlation_time_s: inf   # constant turn-on biases and scale factors\n"
       "installation:\n"
       "  imu_mounting_deg: " << Vec(scenario.imu.mounting_rpy_rad, kRadToDeg) << "\n"
       "  antenna_lever_arm_b_m: " << Vec(scenario.gnss->lever_arm_b_m) << "\n"
       "init:\n"
       "  source: given\n"
       "  nav_file: init.nav\n"
       "  position_std_m: [5, 5, 8]\n"
       "  velocity_std_mps: 0.5\n"
       "  attitude_std_deg: [2, 2, 5]\n";
  if (mag_mode != "off") {
    const YAML::Node errors = YAML::LoadFile(sim_dir + "/errors.yaml");
    RequireUniqueKeys(errors, sim_dir + "/errors.yaml");
    const YAML::Node mag = errors["mag"];
    if (!mag) throw std::runtime_error(sim_dir + "/errors.yaml has no mag section");
    const YAML::Node soft = mag["soft_iron"];
    if (!soft || !soft.IsSequence() || soft.size() != 3) {
      throw std::runtime_error("errors.yaml: mag.soft_iron is not a 3x3 matrix");
    }
    const double noise_uT = std::max(0.3, 3.0 * mag["noise_uT"].as<double>());
    const Eigen::Vector3d field_ned_uT = VecFrom(mag["field_ned_uT"], "mag.field_ned_uT");
    // The heading modes' std: the same per-axis noise over the horizontal intensity
    // (docs/gnss-ins.md, "Magnetometer modes").
    const double heading_std_deg = noise_uT / field_ned_uT.head<2>().norm() * kRadToDeg;
    y << "mag:\n"
         "  mode: " << mag_mode << "\n"
         "  field: {field_ned_uT: " << Vec(field_ned_uT) << "}\n"
         "  hard_iron_uT: " << Vec(VecFrom(mag["hard_iron_uT"], "mag.hard_iron_uT")) << "\n"
         "  soft_iron: [" << Vec(VecFrom(soft[0], "mag.soft_iron")) << ", " << Vec(VecFrom(soft[1], "mag.soft_iron"))
      << ", " << Vec(VecFrom(soft[2], "mag.soft_iron")) << "]\n"
         "  noise_uT: " << Num(noise_uT) << "\n"
         "  heading_std_deg: " << Num(heading_std_deg) << "\n";
  }
  if (scenario.gnss->latency_s != 0.0) {
    y << "gnss:\n"
         "  time_offset_s: " << Num(scenario.gnss->latency_s) << "   # the receiver's latency\n";
  }
  y << "filter:\n"
       "  scale_factors: " << (EstimatesScaleFactors(gyro, accel) ? "true" : "false") << "\n";
  return y.str();
}

}  // namespace navtwin::gnss_ins

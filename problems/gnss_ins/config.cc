// The two configuration loaders of config.h: navtwin's YAML (keys with units in their
// names, docs/gnss-ins.md "Configuration") and KF-GINS' YAML taken unchanged
// (docs/gnss-ins.md "KF-GINS mapping").
#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/gnss_ins/config.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "core/config/yaml_config.h"
#include "core/units.h"
#include "problems/ins/pure_ins.h"

namespace navtwin::gnss_ins {
namespace {


constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------
// Small readers on top of ConfigNode that add the checks this configuration needs.

/// A standard deviation (or any scale that must be positive): > 0 and finite.
double Sigma(const ConfigNode& n, const std::string& key, double fallback) {
  const double v = n.Double(key, fallback);
  if (n.Has(key) && !(v > 0.0)) n.Fail(key, "must be > 0 (a standard deviation or a positive scale)");
  return v;
}

double RequiredSigma(const ConfigNode& n, const std::string& key) {
  if (!n.Has(key)) n.Fail(key, "required");
  return Sigma(n, key, 0.0);
}

double NonNegative(const ConfigNode& n, const std::string& key, double fallback) {
  return n.Double(key, fallback, 0.0, kInf);
}

/// A scalar (every axis) or [x, y, z].
Eigen::Vector3d ScalarOrVector(const ConfigNode& n, const std::string& key,
                               const Eigen::Vector3d& fallback) {
  if (!n.Has(key)) return fallback;
  if (n.yaml()[key].IsScalar()) return Eigen::Vector3d::Constant(n.Double(key, 0.0));
  return n.Vector(key, fallback);
}

/// A positive scalar or [x, y, z] of positive values.
Eigen::Vector3d SigmaVector(const ConfigNode& n, const std::string& key,
                            const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d v = ScalarOrVector(n, key, fallback);
  if (n.Has(key) && !(v.array() > 0.0).all()) {
    n.Fail(key, "every entry must be > 0 (standard deviations)");
  }
  return v;
}

/// A 3x3 matrix written [[a, b, c], [d, e, f], [g, h, i]].
Eigen::Matrix3d Matrix(const ConfigNode& n, const std::string& key, const Eigen::Matrix3d& fallback) {
  if (!n.Has(key)) return fallback;
  const YAML::Node rows = n.yaml()[key];
  if (!rows.IsSequence() || rows.size() != 3) n.Fail(key, "expected [[a, b, c], [d, e, f], [g, h, i]]");
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    const YAML::Node row = rows[r];
    if (!row.IsSequence() || row.size() != 3) n.Fail(key, "expected three rows of three numbers");
    for (int c = 0; c < 3; ++c) {
      try {
        m(r, c) = row[c].as<double>();
      } catch (const YAML::Exception&) {
        n.Fail(key, "expected numbers");
      }
      if (!std::isfinite(m(r, c))) n.Fail(key, "must be finite");
    }
  }
  return m;
}

/// A positive time constant, or .inf / inf (no decay).
double TimeConstant(const ConfigNode& n, const std::string& key, double fallback) {
  if (!n.Has(key)) return fallback;
  const YAML::Node v = n.yaml()[key];
  if (v.IsScalar()) {
    std::string s = v.as<std::string>();
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    if (s == "inf" || s == ".inf" || s == "+inf" || s == "+.inf") return kInf;
  }
  const double x = n.Double(key, fallback);
  if (!(x > 0.0)) n.Fail(key, "must be > 0 (or inf for no decay)");
  return x;
}

/// The folder of a file path ("" for a bare name), for paths written relative to it.
std::string Folder(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string Resolve(const std::string& relative_to_file, const std::string& path) {
  if (path.empty() || path.front() == '/') return path;
  return Folder(relative_to_file) + path;
}

// ---------------------------------------------------------------------------------------
// navtwin YAML sections.

ImuNoise ParseImuNoise(const ConfigNode& n, bool scale_factors) {
  n.RequireKeys({"gyro_arw_deg_sqrt_h", "accel_vrw_m_s_sqrt_h", "gyro_bias_std_deg_h",
                 "accel_bias_std_ug", "gyro_scale_std_ppm", "accel_scale_std_ppm",
                 "correlation_time_s"});
  ImuNoise x;
  x.gyro_arw_rad_per_sqrt_s = RequiredSigma(n, "gyro_arw_deg_sqrt_h") * kDegPerSqrtHour_radpsqrts;
  x.accel_vrw_mps_per_sqrt_s = RequiredSigma(n, "accel_vrw_m_s_sqrt_h") * kMpsPerSqrtHour_mpspsqrts;
  x.gyro_bias_std_radps = RequiredSigma(n, "gyro_bias_std_deg_h") * kDegPerHour_radps;
  x.accel_bias_std_mps2 = RequiredSigma(n, "accel_bias_std_ug") * kMicroG_mps2;
  if (scale_factors) {
    x.gyro_scale_std = RequiredSigma(n, "gyro_scale_std_ppm") * kPpm;
    x.accel_scale_std = RequiredSigma(n, "accel_scale_std_ppm") * kPpm;
  } else {
    x.gyro_scale_std = Sigma(n, "gyro_scale_std_ppm", 0.0) * kPpm;
    x.accel_scale_std = Sigma(n, "accel_scale_std_ppm", 0.0) * kPpm;
  }
  x.correlation_time_s = TimeConstant(n, "correlation_time_s", x.correlation_time_s);
  return x;
}

Installation ParseInstallation(const ConfigNode& n) {
  n.RequireKeys({"imu_mounting_deg", "imu_time_offset_s", "antenna_lever_arm_b_m"});
  Installation x;
  x.imu_mounting_rpy_rad = n.Vector("imu_mounting_deg", Eigen::Vector3d::Zero()) * kDegToRad;
  x.imu_time_offset_s = n.Double("imu_time_offset_s", 0.0);
  x.antenna_lever_arm_b_m = n.Vector("antenna_lever_arm_b_m", Eigen::Vector3d::Zero());
  return x;
}

InitConfig ParseInit(const ConfigNode& n, const std::string& config_path, double start_time_s,
                     bool state_on_command_line) {
  n.RequireKeys({"source", "nav_file", "time_s", "position_deg_m", "velocity_mps", "attitude_deg",
                 "position_std_m", "velocity_std_mps", "attitude_std_deg", "gyro_bias_deg_h",
                 "accel_bias_ug", "gyro_scale_ppm", "accel_scale_ppm", "gyro_bias_std_deg_h",
                 "accel_bias_std_ug", "gyro_scale_std_ppm", "accel_scale_std_ppm",
                 "static_duration_s", "min_speed_mps", "heading", "heading_hypotheses",
                 "heading_search_s"});
  InitConfig x;
  const std::string source = n.String("source", "given");
  if (source == "given") {
    x.source = InitConfig::Source::kGiven;
  } else if (source == "static") {
    x.source = InitConfig::Source::kStaticAlignment;
  } else if (source == "gnss_velocity") {
    x.source = InitConfig::Source::kGnssVelocity;
  } else {
    n.Fail("source", "expected given, static or gnss_velocity, got '" + source + "'");
  }
  const bool has_file = n.Has("nav_file");
  const bool has_values = n.Has("position_deg_m") || n.Has("velocity_mps") || n.Has("attitude_deg");
  if (has_file && has_values) {
    n.Fail("nav_file", "give either nav_file or position_deg_m/velocity_mps/attitude_deg, not both");
  }
  if (x.source == InitConfig::Source::kGiven) {
    if (!has_file && !has_values && !state_on_command_line) {
      n.Fail("source",
             "source: given needs nav_file or position_deg_m, velocity_mps and attitude_deg (or --init_from on the "
             "command line)");
    }
  }
  if (x.source == InitConfig::Source::kGiven && (has_file || has_values)) {
    InsState s;
    if (has_file) {
      if (n.Has("time_s")) n.Fail("time_s", "the time comes from nav_file");
      const std::string nav_file = n.String("nav_file", "");
      if (nav_file.empty()) n.Fail("nav_file", "empty: name the navigation file of the initial state");
      const std::string nav_path = Resolve(config_path, nav_file);
      if (!std::filesystem::is_regular_file(nav_path)) n.Fail("nav_file", "no such file: " + nav_path);
      auto reader = OpenNav(nav_path);
      s.nav = InitialStateFromNav(*reader, std::isfinite(start_time_s)
                                               ? std::optional<double>(start_time_s)
                                               : std::nullopt);
    } else {
      for (const char* key : {"position_deg_m", "velocity_mps", "attitude_deg"}) {
        if (!n.Has(key)) n.Fail(key, "required with source: given (or give nav_file)");
      }
      const Eigen::Vector3d p = n.Vector("position_deg_m", Eigen::Vector3d::Zero());
      if (std::abs(p[0]) > 90.0) n.Fail("position_deg_m", "latitude must be within +-90 deg");
      const Eigen::Vector3d a = n.Vector("attitude_deg", Eigen::Vector3d::Zero()) * kDegToRad;
      // time_s absent: the start time, or (both absent) NaN, which the command replaces
      // by the start of the first IMU interval.
      s.nav.t_s = n.Double("time_s", std::isfinite(start_time_s) ? start_time_s : kNaN);
      s.nav.lat_rad = p[0] * kDegToRad;
      s.nav.lon_rad = p[1] * kDegToRad;
      s.nav.h_m = p[2];
      s.nav.v_n_mps = n.Vector("velocity_mps", Eigen::Vector3d::Zero());
      s.nav.q_n_b = QuatFromEuler(a[0], a[1], a[2]);
    }
    x.state = s;
  } else if (has_file || has_values) {
    n.Fail(has_file ? "nav_file" : "position_deg_m",
           "an initial state is only read with source: given (this source aligns itself)");
  }
  x.imu_errors.bg_radps = ScalarOrVector(n, "gyro_bias_deg_h", Eigen::Vector3d::Zero()) * kDegPerHour_radps;
  x.imu_errors.ba_mps2 = ScalarOrVector(n, "accel_bias_ug", Eigen::Vector3d::Zero()) * kMicroG_mps2;
  x.imu_errors.sg = ScalarOrVector(n, "gyro_scale_ppm", Eigen::Vector3d::Zero()) * kPpm;
  x.imu_errors.sa = ScalarOrVector(n, "accel_scale_ppm", Eigen::Vector3d::Zero()) * kPpm;
  x.std.pos_ned_m = SigmaVector(n, "position_std_m", x.std.pos_ned_m);
  x.std.vel_ned_mps = SigmaVector(n, "velocity_std_mps", x.std.vel_ned_mps);
  x.std.att_rad = SigmaVector(n, "attitude_std_deg", x.std.att_rad / kDegToRad) * kDegToRad;
  // Absent: zero, which means "take the imu_noise value" (InitialStd).
  x.std.bg_radps = SigmaVector(n, "gyro_bias_std_deg_h", Eigen::Vector3d::Zero()) * kDegPerHour_radps;
  x.std.ba_mps2 = SigmaVector(n, "accel_bias_std_ug", Eigen::Vector3d::Zero()) * kMicroG_mps2;
  x.std.sg = SigmaVector(n, "gyro_scale_std_ppm", Eigen::Vector3d::Zero()) * kPpm;
  x.std.sa = SigmaVector(n, "accel_scale_std_ppm", Eigen::Vector3d::Zero()) * kPpm;
  x.static_duration_s = Sigma(n, "static_duration_s", x.static_duration_s);
  x.min_speed_mps = Sigma(n, "min_speed_mps", x.min_speed_mps);
  // The alignment's heading (source: static only); its magnetometer needs mag.mode, which
  // LoadGnssInsConfig checks once the mag section is read.
  const std::string heading = n.String("heading", "auto");
  if (heading == "auto") {
    x.heading = InitConfig::Heading::kAuto;
  } else if (heading == "gyrocompass") {
    x.heading = InitConfig::Heading::kGyrocompass;
  } else if (heading == "magnetometer") {
    x.heading = InitConfig::Heading::kMagnetometer;
  } else if (heading == "search") {
    x.heading = InitConfig::Heading::kSearch;
  } else {
    n.Fail("heading", "expected auto, gyrocompass, magnetometer or search, got '" + heading + "'");
  }
  for (const char* key : {"heading", "heading_hypotheses", "heading_search_s"}) {
    if (n.Has(key) && x.source != InitConfig::Source::kStaticAlignment) {
      n.Fail(key, "only with source: static (the heading of the static alignment)");
    }
  }
  for (const char* key : {"heading_hypotheses", "heading_search_s"}) {
    if (n.Has(key) && x.heading != InitConfig::Heading::kSearch) n.Fail(key, "only with heading: search");
  }
  x.heading_hypotheses = n.Int("heading_hypotheses", x.heading_hypotheses, 2, 360);
  x.heading_search_s = Sigma(n, "heading_search_s", x.heading_search_s);
  return x;
}

MagConfig ParseMag(const ConfigNode& n) {
  n.RequireKeys({"mode", "field", "hard_iron_uT", "soft_iron", "noise_uT", "heading_std_deg",
                 "max_tilt_deg", "min_interval_s"});
  MagConfig x;
  const std::string mode = n.Has("mode") ? n.String("mode", "off") : "off";
  // YAML 1.1 reads a bare `off` as a boolean; yaml-cpp keeps the text, so compare text.
  if (mode == "off" || mode == "false") {
    x.mode = MagConfig::Mode::kOff;
  } else if (mode == "vector") {
    x.mode = MagConfig::Mode::kVector;
  } else if (mode == "heading") {
    x.mode = MagConfig::Mode::kHeading;
  } else if (mode == "heading_2axis") {
    x.mode = MagConfig::Mode::kHeading2Axis;
  } else {
    n.Fail("mode", "expected off, vector, heading or heading_2axis, got '" + mode + "'");
  }
  const ConfigNode f = n.Child("field");
  f.RequireKeys({"declination_deg", "inclination_deg", "intensity_uT", "field_ned_uT"});
  const bool dip_form = f.Has("inclination_deg") || f.Has("intensity_uT");
  bool have_field = false, have_declination = false;
  if (f.Has("field_ned_uT")) {
    if (dip_form) f.Fail("field_ned_uT", "give field_ned_uT or inclination_deg/intensity_uT, not both");
    x.field_ned_uT = f.Vector("field_ned_uT", Eigen::Vector3d::Zero());
    if (!(x.field_ned_uT.head<2>().norm() > 0.0)) f.Fail("field_ned_uT", "has no horizontal component");
    // D = atan2(B_E, B_N), unless stated separately (then it must agree to 0.1 deg).
    const double d = std::atan2(x.field_ned_uT.y(), x.field_ned_uT.x());
    x.declination_rad = d;
    if (f.Has("declination_deg") &&
        std::abs(WrapPi(f.Double("declination_deg", 0.0) * kDegToRad - d)) > 0.1 * kDegToRad) {
      f.Fail("declination_deg", "disagrees with the direction of field_ned_uT");
    }
    have_field = have_declination = true;
  } else {
    if (f.Has("declination_deg")) {
      x.declination_rad = f.Double("declination_deg", 0.0, -180.0, 180.0) * kDegToRad;
      have_declination = true;
    }
    if (dip_form) {
      if (!f.Has("declination_deg") || !f.Has("inclination_deg") || !f.Has("intensity_uT")) {
        f.Fail("", "declination_deg, inclination_deg and intensity_uT go together");
      }
      const double inc = f.Double("inclination_deg", 0.0, -90.0, 90.0) * kDegToRad;
      const double b = Sigma(f, "intensity_uT", 0.0);
      // B [cos I cos D, cos I sin D, sin I] (inclination positive below the horizontal).
      x.field_ned_uT = b * Eigen::Vector3d(std::cos(inc) * std::cos(x.declination_rad),
                                           std::cos(inc) * std::sin(x.declination_rad),
                                           std::sin(inc));
      have_field = true;
    }
  }
  if (x.mode == MagConfig::Mode::kVector && !have_field) {
    n.Fail("field", "mode: vector needs the field: declination_deg, inclination_deg, intensity_uT "
                    "or field_ned_uT");
  }
  if ((x.mode == MagConfig::Mode::kHeading || x.mode == MagConfig::Mode::kHeading2Axis) &&
      !have_declination) {
    n.Fail("field", "heading modes need field.declination_deg (0 only if you mean it)");
  }
  x.iron.hard_iron_uT = n.Vector("hard_iron_uT", Eigen::Vector3d::Zero());
  x.iron.soft_iron = Matrix(n, "soft_iron", Eigen::Matrix3d::Zero());
  if (std::abs((Eigen::Matrix3d::Identity() + x.iron.soft_iron).determinant()) < 1e-6) {
    n.Fail("soft_iron", "I + soft_iron is singular");
  }
  x.noise_uT = Sigma(n, "noise_uT", x.noise_uT);
  x.heading_std_rad = Sigma(n, "heading_std_deg", x.heading_std_rad / kDegToRad) * kDegToRad;
  x.max_tilt_rad = Sigma(n, "max_tilt_deg", x.max_tilt_rad / kDegToRad) * kDegToRad;
  x.min_interval_s = NonNegative(n, "min_interval_s", x.min_interval_s);
  return x;
}

BaroConfig ParseBaro(const ConfigNode& n) {
  n.RequireKeys({"use", "std_m"});
  BaroConfig x;
  x.use = n.Bool("use", x.use);
  x.std_m = Sigma(n, "std_m", x.std_m);
  return x;
}

ZuptConfig ParseZupt(const ConfigNode& n) {
  n.RequireKeys({"enabled", "std_mps", "window_s", "gyro_threshold_deg_s", "accel_std_threshold_mps2",
                 "interval_s"});
  ZuptConfig x;
  x.enabled = n.Bool("enabled", x.enabled);
  x.std_mps = Sigma(n, "std_mps", x.std_mps);
  x.window_s = Sigma(n, "window_s", x.window_s);
  x.gyro_threshold_radps =
      Sigma(n, "gyro_threshold_deg_s", x.gyro_threshold_radps / kDegToRad) * kDegToRad;
  x.accel_std_threshold_mps2 = Sigma(n, "accel_std_threshold_mps2", x.accel_std_threshold_mps2);
  x.interval_s = NonNegative(n, "interval_s", x.interval_s);
  return x;
}

NhcConfig ParseNhc(const ConfigNode& n) {
  n.RequireKeys({"use", "std_mps", "interval_s"});
  NhcConfig x;
  x.enabled = n.Bool("use", x.enabled);
  x.std_mps = Sigma(n, "std_mps", x.std_mps);
  x.interval_s = NonNegative(n, "interval_s", x.interval_s);
  return x;
}

ins::OdometerConfig ParseOdometer(const ConfigNode& n, const std::string& config_path) {
  n.RequireKeys({"file", "std_mps", "scale_std_ppm"});
  ins::OdometerConfig x;
  if (n.Has("file")) x.file = Resolve(config_path, n.String("file", ""));
  x.std_mps = Sigma(n, "std_mps", x.std_mps);
  x.scale_std = NonNegative(n, "scale_std_ppm", x.scale_std * 1e6) * 1e-6;
  return x;
}

VehicleConfig ParseVehicle(const ConfigNode& n) {
  n.RequireKeys({"mounting_rpy_deg", "lever_arm_b_m"});
  VehicleConfig x;
  x.mounting_rpy_rad = n.Vector("mounting_rpy_deg", Eigen::Vector3d::Zero()) * kDegToRad;
  x.lever_arm_b_m = n.Vector("lever_arm_b_m", Eigen::Vector3d::Zero());
  return x;
}

/// The largest |gnss.time_offset_s| accepted.
constexpr double kMaxGnssTimeOffset_s = 1.0;

GnssConfig ParseGnss(const ConfigNode& n) {
  n.RequireKeys({"use_velocity", "pos_std_floor_m", "vel_std_floor_mps", "default_pos_std_m",
                 "default_vel_std_mps", "max_distance_m", "pos_sigma_scale_h", "pos_sigma_scale_v",
                 "vel_sigma_scale_h", "vel_sigma_scale_v", "estimate_lever_arm", "lever_arm_std_m",
                 "estimate_time_offset", "time_offset_s", "time_offset_std_s"});
  GnssConfig x;
  x.use_velocity = n.Bool("use_velocity", x.use_velocity);
  x.pos_std_floor_m = NonNegative(n, "pos_std_floor_m", x.pos_std_floor_m);
  x.vel_std_floor_mps = NonNegative(n, "vel_std_floor_mps", x.vel_std_floor_mps);
  x.default_pos_std_m = Sigma(n, "default_pos_std_m", x.default_pos_std_m);
  x.default_vel_std_mps = Sigma(n, "default_vel_std_mps", x.default_vel_std_mps);
  x.max_distance_m = Sigma(n, "max_distance_m", x.max_distance_m);
  x.pos_sigma_scale_h = Sigma(n, "pos_sigma_scale_h", x.pos_sigma_scale_h);
  x.pos_sigma_scale_v = Sigma(n, "pos_sigma_scale_v", x.pos_sigma_scale_v);
  x.vel_sigma_scale_h = Sigma(n, "vel_sigma_scale_h", x.vel_sigma_scale_h);
  x.vel_sigma_scale_v = Sigma(n, "vel_sigma_scale_v", x.vel_sigma_scale_v);
  x.estimate_lever_arm = n.Bool("estimate_lever_arm", x.estimate_lever_arm);
  x.lever_arm_std_m = SigmaVector(n, "lever_arm_std_m", x.lever_arm_std_m);
  x.estimate_time_offset = n.Bool("estimate_time_offset", x.estimate_time_offset);
  // The model is first order in the offset (factors/gnss_installation.h): receivers' latencies
  // are tens to hundreds of milliseconds.
  x.time_offset_s = n.Double("time_offset_s", x.time_offset_s, -kMaxGnssTimeOffset_s, kMaxGnssTimeOffset_s);
  x.time_offset_std_s = Sigma(n, "time_offset_std_s", x.time_offset_std_s);
  return x;
}

OutageConfig ParseOutages(const ConfigNode& n) {
  n.RequireKeys({"start_s", "len_s", "period_s"});
  OutageConfig x;
  if (!n.Has("start_s")) {
    if (n.Has("len_s") || n.Has("period_s")) n.Fail("start_s", "required with len_s / period_s");
    return x;
  }
  x.start_s = NonNegative(n, "start_s", 0.0);
  x.len_s = RequiredSigma(n, "len_s");
  x.period_s = NonNegative(n, "period_s", 0.0);
  if (x.period_s > 0.0 && x.period_s <= x.len_s) n.Fail("period_s", "must exceed len_s (or be 0)");
  return x;
}

FilterConfig ParseFilter(const ConfigNode& n) {
  n.RequireKeys({"scale_factors", "gate_probability", "store_interval_s", "max_bridge_gap_s",
                 "covariance_interval_s", "gnss_reset_rejections"});
  FilterConfig x;
  x.scale_factors = n.Bool("scale_factors", x.scale_factors);
  x.gate_probability = n.Double("gate_probability", x.gate_probability, 0.0, 1.0);
  if (!(x.gate_probability > 0.0)) n.Fail("gate_probability", "must be in (0, 1] (1: no gating)");
  x.store_interval_s = Sigma(n, "store_interval_s", x.store_interval_s);
  x.max_bridge_gap_s = NonNegative(n, "max_bridge_gap_s", x.max_bridge_gap_s);
  x.covariance_interval_s = NonNegative(n, "covariance_interval_s", x.covariance_interval_s);
  x.gnss_reset_rejections = n.Int("gnss_reset_rejections", x.gnss_reset_rejections, 0, 1000000);
  return x;
}

BatchConfig ParseBatch(const ConfigNode& n) {
  n.RequireKeys({"state_interval_s", "max_state_interval_s", "huber_k", "max_iterations", "threads",
                 "covariance", "relinearize_bias_deg_h", "variance_components", "variance_rounds"});
  BatchConfig x;
  x.state_interval_s = NonNegative(n, "state_interval_s", x.state_interval_s);
  x.max_state_interval_s = Sigma(n, "max_state_interval_s", x.max_state_interval_s);
  x.huber_k = NonNegative(n, "huber_k", x.huber_k);
  x.max_iterations = n.Int("max_iterations", x.max_iterations, 1, 100000);
  x.threads = n.Int("threads", x.threads, 1, 1024);
  x.covariance = n.Bool("covariance", x.covariance);
  x.relinearize_bias_radps =
      NonNegative(n, "relinearize_bias_deg_h", x.relinearize_bias_radps / kDegPerHour_radps) * kDegPerHour_radps;
  x.variance_components = n.Bool("variance_components", x.variance_components);
  x.variance_rounds = n.Int("variance_rounds", x.variance_rounds, 1, 1000);
  return x;
}

// ---------------------------------------------------------------------------------------
// KF-GINS.

/// Line of a key of the root mapping (1-based; 0 unknown).
long KeyLine(const YAML::Node& map, const std::string& key) {
  for (const auto& kv : map) {
    if (kv.first.as<std::string>() == key) return kv.first.Mark().line + 1;
  }
  return 0;
}

/// A KF-GINS list of three numbers.
Eigen::Vector3d KfVector(const ConfigNode& n, const std::string& key, bool required,
                         const Eigen::Vector3d& fallback = Eigen::Vector3d::Zero()) {
  if (!n.Has(key)) {
    if (required) n.Fail(key, "required (KF-GINS configuration)");
    return fallback;
  }
  return n.Vector(key, fallback);
}

Eigen::Vector3d KfSigmaVector(const ConfigNode& n, const std::string& key, bool required,
                              bool zero_allowed = false) {
  const Eigen::Vector3d v = KfVector(n, key, required);
  if (n.Has(key)) {
    const bool ok = zero_allowed ? (v.array() >= 0.0).all() : (v.array() > 0.0).all();
    if (!ok) n.Fail(key, zero_allowed ? "must be >= 0" : "every entry must be > 0 (standard deviations)");
  }
  return v;
}

/// KF-GINS gives noise per axis; the filter takes one value per sensor triad. Equal axes
/// are the normal case; otherwise the largest is used (conservative) with a warning.
double OneValue(const ConfigNode& n, const std::string& key, const Eigen::Vector3d& v) {
  if (v.maxCoeff() != v.minCoeff()) {
    std::cerr << "warning: " << n.file() << ": " << n.path() << "." << key
              << ": the axes differ; navtwin uses one value per triad, the largest ("
              << v.maxCoeff() << ")\n";
  }
  return v.maxCoeff();
}

/// Warns when the IMU file's median sample interval disagrees with imudatarate by more
/// than 10 % (KF-GINS uses the rate only for the first sample; navtwin takes every
/// interval from the time tags, so the rate is only a consistency check).
void CrossCheckRate(const std::string& config_path, long line, const std::string& imu_path,
                    double rate_hz) {
  std::vector<double> dts;
  try {
    auto reader = OpenImu(imu_path);
    ImuSample s;
    while (dts.size() < 201 && reader->Next(&s)) dts.push_back(s.dt_s);
  } catch (const InputError&) {
    return;  // the file will be read (and its errors reported) when the inputs are loaded
  }
  if (dts.size() < 3) return;
  std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
  const double file_rate = 1.0 / dts[dts.size() / 2];
  if (std::abs(file_rate - rate_hz) > 0.1 * rate_hz) {
    std::cerr << "warning: " << config_path << ":line " << line << ": imudatarate " << rate_hz
              << " Hz, but " << imu_path << " has samples at about " << file_rate
              << " Hz (navtwin uses the time tags)\n";
  }
}

/// Keys of a foreign configuration that navtwin does not read, listed on stderr.
void WarnUnused(const std::string& path, const YAML::Node& y, std::initializer_list<const char*> known) {
  std::string ignored;
  for (const auto& kv : y) {
    const std::string key = kv.first.as<std::string>();
    if (std::find_if(known.begin(), known.end(), [&](const char* k) { return key == k; }) == known.end()) {
      ignored += (ignored.empty() ? "" : ", ") + key + " (line " + std::to_string(kv.first.Mark().line + 1) + ")";
    }
  }
  if (!ignored.empty()) {
    std::cerr << "warning: " << path << ": keys navtwin does not use (ignored): " << ignored << "\n";
  }
}

/// OB_GINS imumodel {arw [deg/sqrt(h)], vrw [m/s/sqrt(h)], gbstd [deg/h], abstd [mGal],
/// corrtime [h]}: biases only (OB_GINS estimates no scale factors).
ImuNoise ObginsNoise(const ConfigNode& root) {
  if (!root.Has("imumodel")) root.Fail("imumodel", "required (OB_GINS configuration)");
  const ConfigNode m = root.Child("imumodel");
  m.RequireKeys({"arw", "vrw", "gbstd", "abstd", "corrtime"});
  for (const char* key : {"arw", "vrw", "gbstd", "abstd", "corrtime"}) {
    if (!m.Has(key)) m.Fail(key, "required (OB_GINS configuration)");
  }
  ImuNoise n;
  n.gyro_arw_rad_per_sqrt_s = Sigma(m, "arw", 1.0) * kDegPerSqrtHour_radpsqrts;
  n.accel_vrw_mps_per_sqrt_s = Sigma(m, "vrw", 1.0) * kMpsPerSqrtHour_mpspsqrts;
  n.gyro_bias_std_radps = Sigma(m, "gbstd", 1.0) * kDegPerHour_radps;
  n.accel_bias_std_mps2 = Sigma(m, "abstd", 1.0) * kMilliGal_mps2;
  n.correlation_time_s = Sigma(m, "corrtime", 1.0) * kHour_s;
  return n;
}

/// OB_GINS initialisation: velocity and attitude given, the position from the first GNSS
/// fix at or after starttime. OB_GINS gives no initial sigmas; navtwin takes these.
void ObginsInit(const ConfigNode& root, GnssInsConfig* c) {
  const Eigen::Vector3d vel = KfVector(root, "initvel", true);
  const Eigen::Vector3d att = KfVector(root, "initatt", true);
  InsState s;
  s.nav.t_s = c->start_time_s;
  s.nav.v_n_mps = vel;
  s.nav.q_n_b = QuatFromEuler(att[0] * kDegToRad, att[1] * kDegToRad, att[2] * kDegToRad);
  c->init.source = InitConfig::Source::kGiven;
  c->init.position_from_gnss = true;
  c->init.imu_errors.bg_radps = KfVector(root, "initgb", false) * kDegPerHour_radps;
  c->init.imu_errors.ba_mps2 = KfVector(root, "initab", false) * kMilliGal_mps2;
  s.imu = c->init.imu_errors;
  c->init.state = s;
  c->init.std.pos_ned_m = Eigen::Vector3d::Constant(1.0);
  c->init.std.vel_ned_mps = Eigen::Vector3d::Constant(0.5);
  c->init.std.att_rad = Eigen::Vector3d(1.0, 1.0, 5.0) * kDegToRad;
}

/// OB_GINS odometer {isuseodo, std [m/s] (forward, lateral, vertical), srw [ppm]}, odolever,
/// bodyangle: the odometer column of the IMU file and the NHC.
void ObginsVehicle(const ConfigNode& root, GnssInsConfig* c) {
  c->vehicle.lever_arm_b_m = KfVector(root, "odolever", false);
  c->vehicle.mounting_rpy_rad = KfVector(root, "bodyangle", false) * kDegToRad;
  const ConfigNode odo = root.Child("odometer");
  odo.RequireKeys({"isuseodo", "std", "srw"});
  if (!odo.Bool("isuseodo", false)) return;
  if (root.Int("imudatalen", 7, 7, 1000) < 8) {
    root.Fail("imudatalen", "odometer.isuseodo needs the odometer column: imudatalen 8 or more");
  }
  const Eigen::Vector3d std = KfSigmaVector(odo, "std", true);
  c->odometer.file = c->imu_path;
  c->odometer.from_imu_file = true;
  c->odometer.std_mps = std[0];
  c->odometer.scale_std = odo.NonNegative("srw", 100.0) * kPpm;
  c->nhc.enabled = true;
  c->nhc.std_mps = std::max(std[1], std[2]);
}

}  // namespace

GnssInsConfig LoadGnssInsConfig(const std::string& path, bool init_state_on_command_line) {
  const ConfigNode root = LoadYamlFile(path);
  root.RequireKeys({"imu_noise", "installation", "init", "mag", "baro", "zupt", "nhc", "odometer", "vehicle", "gnss",
                    "outages", "filter", "batch", "output_rate_hz", "std_rate_hz", "start_s", "end_s"});
  if (!root.Has("imu_noise")) root.Fail("imu_noise", "required");
  GnssInsConfig c;
  c.start_time_s = root.Double("start_s", c.start_time_s);
  c.end_time_s = root.Double("end_s", c.end_time_s);
  if (!(c.end_time_s > c.start_time_s)) root.Fail("end_s", "must be after start_s");
  c.output_rate_hz = root.Double("output_rate_hz", 0.0, 0.0, 1e6);
  c.std_rate_hz = root.Double("std_rate_hz", c.std_rate_hz, 0.0, 1e6);
  c.filter = ParseFilter(root.Child("filter"));
  c.imu_noise = ParseImuNoise(root.Child("imu_noise"), c.filter.scale_factors);
  c.installation = ParseInstallation(root.Child("installation"));
  c.init = ParseInit(root.Child("init"), path, c.start_time_s, init_state_on_command_line);
  c.mag = ParseMag(root.Child("mag"));
  if (c.init.heading == InitConfig::Heading::kMagnetometer && c.mag.mode == MagConfig::Mode::kOff) {
    root.Child("init").Fail("heading", "magnetometer needs a magnetometer (mag.mode other than off)");
  }
  c.baro = ParseBaro(root.Child("baro"));
  c.zupt = ParseZupt(root.Child("zupt"));
  c.nhc = ParseNhc(root.Child("nhc"));
  c.odometer = ParseOdometer(root.Child("odometer"), path);
  c.vehicle = ParseVehicle(root.Child("vehicle"));
  c.gnss = ParseGnss(root.Child("gnss"));
  c.outages = ParseOutages(root.Child("outages"));
  c.batch = ParseBatch(root.Child("batch"));
  return c;
}

GnssInsConfig LoadKfginsConfig(const std::string& path) {
  const ConfigNode root = LoadYamlFile(path);
  const YAML::Node& y = root.yaml();
  if (!y.IsMap()) root.Fail("", "expected a mapping of keys to values (a KF-GINS configuration)");
  static const char* const kKnown[] = {
      "imupath",     "gnsspath",    "outputpath",   "imudatalen",   "imudatarate", "starttime",
      "endtime",     "initpos",     "initvel",      "initatt",      "initgyrbias", "initaccbias",
      "initgyrscale", "initaccscale", "initposstd", "initvelstd",   "initattstd",  "initbgstd",
      "initbastd",   "initsgstd",   "initsastd",    "imunoise",     "antlever"};
  // KF-GINS files carry options of its variants (e.g. odometer settings): tolerated and
  // listed, so that a user sees what navtwin does not use.
  std::string ignored;
  for (const auto& kv : y) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(std::begin(kKnown), std::end(kKnown), key) == std::end(kKnown)) {
      ignored += (ignored.empty() ? "" : ", ") + key + " (line " +
                 std::to_string(kv.first.Mark().line + 1) + ")";
    }
  }
  if (!ignored.empty()) {
    std::cerr << "warning: " << path << ": keys navtwin does not use (ignored): " << ignored << "\n";
  }

  GnssInsConfig c;
  c.imu_path = root.String("imupath", "");
  c.gnss_path = root.String("gnsspath", "");
  c.output_path = root.String("outputpath", "");
  if (root.Has("imudatalen")) {
    const int len = root.Int("imudatalen", 7, 7, 1000);
    (void)len;  // the readers detect the column count themselves
  }
  if (!root.Has("starttime")) root.Fail("starttime", "required (KF-GINS configuration)");
  if (!root.Has("endtime")) root.Fail("endtime", "required (KF-GINS configuration)");
  c.start_time_s = root.Double("starttime", 0.0);
  const double end = root.Double("endtime", -1.0);
  c.end_time_s = end < 0.0 ? kInf : end;  // KF-GINS: -1 = to the end of the IMU file
  if (!(c.end_time_s > c.start_time_s)) root.Fail("endtime", "must be after starttime (or -1)");
  // KF-GINS uses every fix (no innovation gate): so does the filter, unless --gate_probability.
  c.filter.gate_probability = 1.0;

  // Initial state at starttime, given.
  const Eigen::Vector3d pos = KfVector(root, "initpos", true);  // deg, deg, m
  const Eigen::Vector3d vel = KfVector(root, "initvel", true);  // m/s NED
  const Eigen::Vector3d att = KfVector(root, "initatt", true);  // deg roll, pitch, yaw (ZYX)
  if (std::abs(pos[0]) > 90.0) root.Fail("initpos", "latitude must be within +-90 deg");
  InsState s;
  s.nav.t_s = c.start_time_s;
  s.nav.lat_rad = pos[0] * kDegToRad;
  s.nav.lon_rad = pos[1] * kDegToRad;
  s.nav.h_m = pos[2];
  s.nav.v_n_mps = vel;
  s.nav.q_n_b = QuatFromEuler(att[0] * kDegToRad, att[1] * kDegToRad, att[2] * kDegToRad);
  c.init.source = InitConfig::Source::kGiven;
  c.init.imu_errors.bg_radps = KfVector(root, "initgyrbias", true) * kDegPerHour_radps;
  c.init.imu_errors.ba_mps2 = KfVector(root, "initaccbias", true) * kMilliGal_mps2;
  c.init.imu_errors.sg = KfVector(root, "initgyrscale", true) * kPpm;
  c.init.imu_errors.sa = KfVector(root, "initaccscale", true) * kPpm;
  s.imu = c.init.imu_errors;
  c.init.state = s;
  c.init.std.pos_ned_m = KfSigmaVector(root, "initposstd", true);
  c.init.std.vel_ned_mps = KfSigmaVector(root, "initvelstd", true);
  // KF-GINS gives roll/pitch/yaw sigmas; navtwin's attitude error is phi_n (NED axes),
  // equal to them to first order for a level attitude (docs/gnss-ins.md).
  c.init.std.att_rad = KfSigmaVector(root, "initattstd", true) * kDegToRad;
  // Optional: absent (zero) means "take the imunoise value", as in KF-GINS.
  c.init.std.bg_radps = KfSigmaVector(root, "initbgstd", false) * kDegPerHour_radps;
  c.init.std.ba_mps2 = KfSigmaVector(root, "initbastd", false) * kMilliGal_mps2;
  c.init.std.sg = KfSigmaVector(root, "initsgstd", false) * kPpm;
  c.init.std.sa = KfSigmaVector(root, "initsastd", false) * kPpm;

  const ConfigNode noise = root.Child("imunoise");
  if (!root.Has("imunoise")) root.Fail("imunoise", "required (KF-GINS configuration)");
  noise.RequireKeys({"arw", "vrw", "gbstd", "abstd", "gsstd", "asstd", "corrtime"});
  c.imu_noise.gyro_arw_rad_per_sqrt_s =
      OneValue(noise, "arw", KfSigmaVector(noise, "arw", true)) * kDegPerSqrtHour_radpsqrts;
  c.imu_noise.accel_vrw_mps_per_sqrt_s = OneValue(noise, "vrw", KfSigmaVector(noise, "vrw", true)) * kMpsPerSqrtHour_mpspsqrts;
  c.imu_noise.gyro_bias_std_radps =
      OneValue(noise, "gbstd", KfSigmaVector(noise, "gbstd", true)) * kDegPerHour_radps;
  c.imu_noise.accel_bias_std_mps2 =
      OneValue(noise, "abstd", KfSigmaVector(noise, "abstd", true)) * kMilliGal_mps2;
  // Scale factors: KF-GINS always estimates them (21 states); a zero gsstd/asstd turns
  // them off here (15 states), since a zero standard deviation means "not estimated".
  const Eigen::Vector3d gs = KfSigmaVector(noise, "gsstd", true, /*zero_allowed=*/true);
  const Eigen::Vector3d as = KfSigmaVector(noise, "asstd", true, /*zero_allowed=*/true);
  c.filter.scale_factors = (gs.array() > 0.0).all() && (as.array() > 0.0).all();
  if (!c.filter.scale_factors && (gs.maxCoeff() > 0.0 || as.maxCoeff() > 0.0)) {
    std::cerr << "warning: " << path << ": imunoise gsstd/asstd has a zero entry: scale factors "
                 "are not estimated (15-state filter)\n";
  }
  if (c.filter.scale_factors) {
    c.imu_noise.gyro_scale_std = OneValue(noise, "gsstd", gs) * kPpm;
    c.imu_noise.accel_scale_std = OneValue(noise, "asstd", as) * kPpm;
  }
  if (!noise.Has("corrtime")) noise.Fail("corrtime", "required (KF-GINS configuration)");
  const double corr_h = noise.Double("corrtime", 0.0);
  if (!(corr_h > 0.0)) noise.Fail("corrtime", "must be > 0 (hours)");
  c.imu_noise.correlation_time_s = corr_h * kHour_s;
  // Antenna lever arm: IMU frame = body frame (KF-GINS has no mounting rotation).
  c.installation.antenna_lever_arm_b_m = KfVector(root, "antlever", true);

  if (root.Has("imudatarate")) {
    const double rate = root.Double("imudatarate", 0.0);
    if (!(rate > 0.0)) root.Fail("imudatarate", "must be > 0 (Hz)");
    if (!c.imu_path.empty()) CrossCheckRate(path, KeyLine(y, "imudatarate"), c.imu_path, rate);
  }
  return c;
}

GnssInsConfig LoadObginsConfig(const std::string& path) {
  const ConfigNode root = LoadYamlFile(path);
  const YAML::Node& y = root.yaml();
  if (!y.IsMap()) root.Fail("", "expected a mapping of keys to values (an OB_GINS configuration)");
  WarnUnused(path, y, {"imufile", "gnssfile", "outputpath", "starttime", "endtime", "initvel", "initatt", "initgb",
                       "initab", "imudatalen", "imudatarate", "antlever", "odolever", "bodyangle", "odometer",
                       "imumodel", "isuseoutage", "outagetime", "outagelen", "outageperiod"});
  GnssInsConfig c;
  // Relative paths are taken relative to the current directory, as OB_GINS does.
  c.imu_path = root.String("imufile", "");
  c.gnss_path = root.String("gnssfile", "");
  c.output_path = root.String("outputpath", "");
  for (const char* key : {"starttime", "endtime"}) {
    if (!root.Has(key)) root.Fail(key, "required (OB_GINS configuration)");
  }
  c.start_time_s = root.Double("starttime", 0.0);
  const double end = root.Double("endtime", -1.0);
  c.end_time_s = end <= 0.0 ? kInf : end;  // OB_GINS: 0 or -1 = to the end of the IMU file
  if (!(c.end_time_s > c.start_time_s)) root.Fail("endtime", "must be after starttime (or 0 / -1)");
  ObginsInit(root, &c);
  c.imu_noise = ObginsNoise(root);
  c.installation.antenna_lever_arm_b_m = KfVector(root, "antlever", true);
  ObginsVehicle(root, &c);
  if (root.Bool("isuseoutage", false)) {
    // OB_GINS gives the first outage in GPS seconds; navtwin counts from the start.
    c.outages.start_s = root.Double("outagetime", c.start_time_s) - c.start_time_s;
    c.outages.len_s = root.Positive("outagelen", 60.0);
    c.outages.period_s = root.NonNegative("outageperiod", 0.0);
    if (c.outages.start_s < 0.0) root.Fail("outagetime", "must be at or after starttime");
  }
  return c;
}

}  // namespace navtwin::gnss_ins

#include "core/sim/scenario.h"

#include <cmath>

#include "core/rotation.h"
#include "core/sim/calibration_rig.h"
#include "core/sim/presets.h"
#include "core/sim/segments.h"

namespace navtwin::sim {
namespace {

wgs84::Geodetic ParseStart(const ConfigNode& node) {
  node.RequireKeys({"lat_deg", "lon_deg", "h_m"});
  wgs84::Geodetic g;
  g.lat_rad = node.Double("lat_deg", 37.5, -89.0, 89.0) * kDegToRad;
  g.lon_rad = node.Double("lon_deg", 127.0, -180.0, 360.0) * kDegToRad;
  g.h_m = node.Double("h_m", 0.0, -500.0, 50000.0);
  return g;
}

InitErrorConfig ParseInitErrors(const ConfigNode& node) {
  node.RequireKeys({"position_ned_m", "velocity_ned_mps", "attitude_deg", "attitude_arcmin"});
  InitErrorConfig c;
  c.position_ned_m = node.Vector("position_ned_m", Eigen::Vector3d::Zero());
  c.velocity_ned_mps = node.Vector("velocity_ned_mps", Eigen::Vector3d::Zero());
  if (node.Has("attitude_deg") && node.Has("attitude_arcmin")) {
    node.Fail("attitude_arcmin", "give attitude_deg or attitude_arcmin, not both");
  }
  c.attitude_phi_n_rad = node.Vector("attitude_deg", Eigen::Vector3d::Zero()) * kDegToRad +
                         node.Vector("attitude_arcmin", Eigen::Vector3d::Zero()) * kArcmin_rad;
  return c;
}

}  // namespace

Scenario ParseScenario(const ConfigNode& root) {
  root.RequireKeys({"name", "description", "duration_s", "start", "trajectory", "imu", "gnss",
                    "mag", "baro", "odometer", "master", "init_errors"});
  Scenario s;
  s.name = root.String("name", "unnamed");
  s.description = root.String("description", "");
  s.start = ParseStart(root.Child("start"));
  if (!root.Has("trajectory")) root.Fail("trajectory", "required");
  const ConfigNode trajectory = root.Child("trajectory");
  const std::string kind = trajectory.String("kind", "segments");
  double trajectory_duration_s = 0.0;
  if (kind == "multiposition" || kind == "pendulum" || kind == "handheld") {
    std::shared_ptr<CalibrationRig> rig = MakeCalibrationRig(ParseCalibrationRigConfig(trajectory));
    s.emit_trajectory = [rig](YAML::Emitter& out) { rig->EmitDrawn(out); };
    // A schedule's own length is the default duration (a hand-placed sequence's is drawn).
    if (const auto* table = dynamic_cast<const MultiPositionRig*>(rig.get())) trajectory_duration_s = table->duration_s();
    s.trajectory = rig;
  } else if (kind == "segments") {
    auto segments = std::make_shared<SegmentTrajectory>(ParseTrajectoryConfig(trajectory));
    trajectory_duration_s = segments->duration_s();
    s.trajectory = segments;
  } else {
    trajectory.Fail("kind", "unknown trajectory kind '" + kind +
                                "' (segments, multiposition, pendulum, handheld)");
  }
  s.duration_s = root.Double("duration_s", trajectory_duration_s, 0.0, 30.0 * kSecondsPerDay);
  if (!(s.duration_s > 0.0)) root.Fail("duration_s", "required (> 0) for this trajectory kind");
  s.imu = ParseImuSimConfig(root.Child("imu"));
  if (root.Has("gnss")) s.gnss = ParseGnssSimConfig(root.Child("gnss"));
  if (root.Has("mag")) s.mag = ParseMagSimConfig(root.Child("mag"));
  if (root.Has("baro")) s.baro = ParseBaroSimConfig(root.Child("baro"));
  if (root.Has("odometer")) s.odometer = ParseOdometerSimConfig(root.Child("odometer"));
  if (root.Has("master")) s.master = ParseMasterSimConfig(root.Child("master"));
  s.init_errors = ParseInitErrors(root.Child("init_errors"));
  return s;
}

Scenario LoadScenario(const std::string& preset_or_path) {
  if (const std::optional<std::string> text = PresetYaml(preset_or_path)) {
    return ParseScenario(ParseYaml(*text, "preset " + preset_or_path));
  }
  return ParseScenario(LoadYamlFile(preset_or_path));
}

}  // namespace navtwin::sim

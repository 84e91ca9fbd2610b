// Reading a YAML configuration (the simulator's scenarios, the problems' configurations,
// calibration files) with errors that name the file, the line and the key path (e.g. "scenario.yaml:line 12: field 'imu.gyro.arw_deg_sqrt_h': must be
// >= 0"). Unknown keys are errors, so a typo never silently falls back to a default.
// Keys carry their units (bias_deg_h, arw_deg_sqrt_h, rate_hz, lever_arm_b_m); readers
// convert them to SI with core/units.h as they read, so structs hold SI only.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

namespace navtwin {

/// A YAML mapping with the file it came from and its key path, for messages.
class ConfigNode {
 public:
  ConfigNode(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

  /// Throws InputError unless the node is a mapping (or absent/null, which reads as empty)
  /// whose keys are all in `allowed`.
  void RequireKeys(std::initializer_list<const char*> allowed) const;

  bool Has(const std::string& key) const;
  ConfigNode Child(const std::string& key) const;  ///< an absent child reads as empty
  /// The elements of a sequence (absent: empty); each named path[i].
  std::vector<ConfigNode> Elements(const std::string& key) const;

  double Double(const std::string& key, double fallback) const;
  /// Like Double, and throws unless lo <= value <= hi.
  double Double(const std::string& key, double fallback, double lo, double hi) const;
  /// A standard deviation or another scale: finite and > 0 ("must be > 0, got X").
  double Positive(const std::string& key, double fallback) const;
  /// A noise density or bias size where 0 means none: finite and >= 0.
  double NonNegative(const std::string& key, double fallback) const;
  /// Positive / NonNegative of a key in a people unit (named in the key, e.g. bias_deg_h),
  /// returned in SI: value * unit_si, e.g. unit_si = kDegPerHour_radps (core/units.h). An
  /// absent key returns fallback_si unchanged (already SI).
  double PositiveSi(const std::string& key, double unit_si, double fallback_si) const;
  double NonNegativeSi(const std::string& key, double unit_si, double fallback_si) const;
  double RequiredDouble(const std::string& key) const;
  int Int(const std::string& key, int fallback, int lo, int hi) const;
  bool Bool(const std::string& key, bool fallback) const;
  std::string String(const std::string& key, const std::string& fallback) const;
  /// A 3-vector written [x, y, z].
  Eigen::Vector3d Vector(const std::string& key, const Eigen::Vector3d& fallback) const;
  /// A [lo, hi] pair with lo <= hi.
  Eigen::Vector2d Range(const std::string& key, const Eigen::Vector2d& fallback) const;

  const YAML::Node& yaml() const { return node_; }
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  /// InputError at this node (or its child `key`) with the given reason.
  [[noreturn]] void Fail(const std::string& key, const std::string& reason) const;

 private:
  std::string KeyPath(const std::string& key) const;
  long Line(const std::string& key) const;
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

/// errors.yaml output: `key: [x, y, z]` / `key: [[..], [..], [..]]` with each SI value
/// divided by `per_unit`, the SI size of the unit named in the key (e.g. kDegToRad for a
/// key ending in _deg).
void EmitVector(YAML::Emitter& out, const std::string& key, const Eigen::Vector3d& v_si,
                double per_unit = 1.0);
void EmitMatrix(YAML::Emitter& out, const std::string& key, const Eigen::Matrix3d& m_si,
                double per_unit = 1.0);

/// Throws InputError naming `file`, the line and the key path (e.g. "imu.rate_hz") when a
/// mapping anywhere under `root` repeats a key: yaml-cpp keeps both pairs and a lookup
/// takes the first, so the second value would be ignored without a word. Every loader of
/// a YAML or JSON input calls this (ParseYaml and LoadYamlFile do).
void RequireUniqueKeys(const YAML::Node& root, const std::string& file);

/// Parses YAML text (from a file or a built-in preset named `file`) into a root node;
/// syntax errors and repeated keys become InputError with the line.
ConfigNode ParseYaml(const std::string& text, const std::string& file);
ConfigNode LoadYamlFile(const std::string& path);

}  // namespace navtwin

// Configuration helpers shared by the aiding-sensor simulators (core/sim/aiding_*.cc):
// the YAML shapes their keys take, and the errors.yaml writer.
#pragma once

#include <string>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include "core/config/yaml_config.h"

namespace navtwin::sim::aiding_config {

/// Fails unless at most one of sigma_key (a per-run draw) and fixed_key (fixed values) is given.
void RequireNotBoth(const ConfigNode& node, const std::string& sigma_key, const std::string& fixed_key);

/// A 1-sigma per NED axis: a scalar (every axis), [horizontal, vertical] or [N, E, D];
/// every value >= 0; absent: 0.
Eigen::Vector3d SigmaNed(const ConfigNode& node, const std::string& key);

/// [[a, b, c], [d, e, f], [g, h, i]] of finite numbers.
Eigen::Matrix3d Matrix3x3(const ConfigNode& node, const std::string& key);

/// An element [start_s, end_s] of a list, start < end.
Eigen::Vector2d Interval(const ConfigNode& element);

/// The key rate_hz in [0.1, hi]; absent: fallback.
double Rate(const ConfigNode& node, double fallback, double hi);

/// key: value in an errors.yaml mapping.
void EmitValue(YAML::Emitter& out, const std::string& key, double value);

}  // namespace navtwin::sim::aiding_config

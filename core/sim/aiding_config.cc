#include "core/sim/aiding_config.h"

#include <cmath>
#include <vector>

namespace navtwin::sim::aiding_config {
namespace {

/// The numbers of a YAML sequence node (or a scalar as one number); Fail on anything else.
std::vector<double> Numbers(const ConfigNode& node, const std::string& key) {
  const YAML::Node v = node.yaml()[key];
  std::vector<double> out;
  if (v.IsScalar()) return {node.Double(key, 0.0)};
  if (!v.IsSequence()) node.Fail(key, "expected a number or a list of numbers");
  for (const YAML::Node& e : v) {
    try {
      out.push_back(e.as<double>());
    } catch (const YAML::Exception&) {
      node.Fail(key, "expected a list of numbers");
    }
    if (!std::isfinite(out.back())) node.Fail(key, "must be finite");
  }
  return out;
}

}  // namespace

void RequireNotBoth(const ConfigNode& node, const std::string& sigma_key,
                    const std::string& fixed_key) {
  if (node.Has(sigma_key) && node.Has(fixed_key)) {
    node.Fail(fixed_key, "give either " + sigma_key + " (1-sigma of a per-run draw) or " +
                             fixed_key + " (fixed values), not both");
  }
}

Eigen::Vector3d SigmaNed(const ConfigNode& node, const std::string& key) {
  if (!node.Has(key)) return Eigen::Vector3d::Zero();
  const std::vector<double> v = Numbers(node, key);
  Eigen::Vector3d sigma;
  if (v.size() == 1) {
    sigma.setConstant(v[0]);
  } else if (v.size() == 2) {
    sigma << v[0], v[0], v[1];
  } else if (v.size() == 3) {
    sigma << v[0], v[1], v[2];
  } else {
    node.Fail(key, "expected a number, [horizontal, vertical] or [N, E, D]");
  }
  if (sigma.minCoeff() < 0.0) node.Fail(key, "must be >= 0");
  return sigma;
}

Eigen::Matrix3d Matrix3x3(const ConfigNode& node, const std::string& key) {
  const YAML::Node m = node.yaml()[key];
  const char* shape = "expected [[a, b, c], [d, e, f], [g, h, i]] of finite numbers";
  if (!m.IsSequence() || m.size() != 3) node.Fail(key, shape);
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    if (!m[r].IsSequence() || m[r].size() != 3) node.Fail(key, shape);
    for (int c = 0; c < 3; ++c) {
      try {
        out(r, c) = m[r][c].as<double>();
      } catch (const YAML::Exception&) {
        node.Fail(key, shape);
      }
    }
  }
  if (!out.allFinite()) node.Fail(key, shape);
  return out;
}

Eigen::Vector2d Interval(const ConfigNode& element) {
  const YAML::Node& v = element.yaml();
  const char* shape = "expected [start_s, end_s] with start_s < end_s";
  if (!v.IsSequence() || v.size() != 2) element.Fail("", shape);
  Eigen::Vector2d out;
  for (int i = 0; i < 2; ++i) {
    try {
      out[i] = v[i].as<double>();
    } catch (const YAML::Exception&) {
      element.Fail("", shape);
    }
  }
  if (!out.allFinite() || !(out[0] < out[1])) element.Fail("", shape);
  return out;
}

double Rate(const ConfigNode& node, double fallback, double hi) {
  return node.Double("rate_hz", fallback, 0.1, hi);
}

void EmitValue(YAML::Emitter& out, const std::string& key, double value) {
  out << YAML::Key << key << YAML::Value << value;
}

}  // namespace navtwin::sim::aiding_config

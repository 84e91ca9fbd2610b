#include "core/config/yaml_config.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "core/io/input_error.h"

namespace navtwin {

std::string ConfigNode::KeyPath(const std::string& key) const {
  if (key.empty()) return path_;
  return path_.empty() ? key : path_ + "." + key;
}

long ConfigNode::Line(const std::string& key) const {
  if (!key.empty() && node_.IsMap() && node_[key]) return node_[key].Mark().line + 1;
  return node_.IsDefined() && !node_.IsNull() ? node_.Mark().line + 1 : 0;
}

void ConfigNode::Fail(const std::string& key, const std::string& reason) const {
  throw InputError(file_, Line(key), KeyPath(key), reason);
}

void ConfigNode::RequireKeys(std::initializer_list<const char*> allowed) const {
  if (!node_.IsDefined() || node_.IsNull()) return;
  if (!node_.IsMap()) Fail("", "expected a mapping of keys to values");
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    bool known = false;
    for (const char* a : allowed) known = known || key == a;
    if (!known) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      throw InputError(file_, kv.first.Mark().line + 1, KeyPath(key),
                       "unknown key (known here: " + list + ")");
    }
  }
}

bool ConfigNode::Has(const std::string& key) const {
  return node_.IsMap() && node_[key] && !node_[key].IsNull();
}

ConfigNode ConfigNode::Child(const std::string& key) const {
  return ConfigNode(Has(key) ? node_[key] : YAML::Node(), file_, KeyPath(key));
}

std::vector<ConfigNode> ConfigNode::Elements(const std::string& key) const {
  std::vector<ConfigNode> out;
  if (!Has(key)) return out;
  const YAML::Node seq = node_[key];
  if (!seq.IsSequence()) Fail(key, "expected a list");
  for (std::size_t i = 0; i < seq.size(); ++i) {
    out.emplace_back(seq[i], file_, KeyPath(key) + "[" + std::to_string(i) + "]");
  }
  return out;
}

double ConfigNode::Double(const std::string& key, double fallback) const {
  if (!Has(key)) return fallback;
  double v;
  try {
    v = node_[key].as<double>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected a number");
  }
  if (!std::isfinite(v)) Fail(key, "must be finite");
  return v;
}

double ConfigNode::Double(const std::string& key, double fallback, double lo, double hi) const {
  const double v = Double(key, fallback);
  if (v < lo || v > hi) {
    std::ostringstream m;
    m << "must be in [" << lo << ", " << hi << "], got " << v;
    Fail(key, m.str());
  }
  return v;
}

double ConfigNode::Positive(const std::string& key, double fallback) const {
  const double v = Double(key, fallback);
  if (Has(key) && !(v > 0.0)) {
    std::ostringstream m;
    m << "must be > 0, got " << v;
    Fail(key, m.str());
  }
  return v;
}

double ConfigNode::PositiveSi(const std::string& key, double unit_si, double fallback_si) const {
  return Has(key) ? Positive(key, 0.0) * unit_si : fallback_si;
}

double ConfigNode::NonNegativeSi(const std::string& key, double unit_si, double fallback_si) const {
  return Has(key) ? NonNegative(key, 0.0) * unit_si : fallback_si;
}

double ConfigNode::NonNegative(const std::string& key, double fallback) const {
  const double v = Double(key, fallback);
  if (Has(key) && !(v >= 0.0)) {
    std::ostringstream m;
    m << "must be >= 0, got " << v;
    Fail(key, m.str());
  }
  return v;
}

double ConfigNode::RequiredDouble(const std::string& key) const {
  if (!Has(key)) Fail(key, "required");
  return Double(key, 0.0);
}

int ConfigNode::Int(const std::string& key, int fallback, int lo, int hi) const {
  if (!Has(key)) return fallback;
  int v;
  try {
    v = node_[key].as<int>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected a whole number");
  }
  if (v < lo || v > hi) {
    Fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                  std::to_string(v));
  }
  return v;
}

bool ConfigNode::Bool(const std::string& key, bool fallback) const {
  if (!Has(key)) return fallback;
  try {
    return node_[key].as<bool>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected true or false");
  }
}

std::string ConfigNode::String(const std::string& key, const std::string& fallback) const {
  if (!Has(key)) return fallback;
  if (!node_[key].IsScalar()) Fail(key, "expected a text value");
  return node_[key].as<std::string>();
}

Eigen::Vector3d ConfigNode::Vector(const std::string& key, const Eigen::Vector3d& fallback) const {
  if (!Has(key)) return fallback;
  const YAML::Node seq = node_[key];
  if (!seq.IsSequence() || seq.size() != 3) Fail(key, "expected [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    try {
      v[i] = seq[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, "expected [x, y, z] of numbers");
    }
    if (!std::isfinite(v[i])) Fail(key, "must be finite");
  }
  return v;
}

Eigen::Vector2d ConfigNode::Range(const std::string& key, const Eigen::Vector2d& fallback) const {
  if (!Has(key)) return fallback;
  const YAML::Node seq = node_[key];
  if (!seq.IsSequence() || seq.size() != 2) Fail(key, "expected [lo, hi]");
  Eigen::Vector2d v;
  for (int i = 0; i < 2; ++i) {
    try {
      v[i] = seq[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, "expected [lo, hi] of numbers");
    }
  }
  if (!(v[0] <= v[1]) || !v.allFinite()) Fail(key, "expected finite lo <= hi");
  return v;
}

void EmitVector(YAML::Emitter& out, const std::string& key, const Eigen::Vector3d& v_si,
                double per_unit) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < 3; ++i) out << v_si[i] / per_unit;
  out << YAML::EndSeq;
}

void EmitMatrix(YAML::Emitter& out, const std::string& key, const Eigen::Matrix3d& m_si,
                double per_unit) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (int r = 0; r < 3; ++r) {
    out << YAML::BeginSeq;
    for (int c = 0; c < 3; ++c) out << m_si(r, c) / per_unit;
    out << YAML::EndSeq;
  }
  out << YAML::EndSeq;
}

void RequireUniqueKeys(const YAML::Node& root, const std::string& file) {
  // Depth first in file order without recursion; a node reached again through an alias
  // (same position in the text) is walked once.
  std::vector<std::pair<YAML::Node, std::string>> pending = {{root, ""}};
  std::set<int> walked;
  while (!pending.empty()) {
    const YAML::Node node = pending.back().first;
    const std::string path = pending.back().second;
    pending.pop_back();
    if (!node.IsMap() && !node.IsSequence()) continue;
    if (node.Mark().pos >= 0 && !walked.insert(node.Mark().pos).second) continue;
    std::vector<std::pair<YAML::Node, std::string>> children;
    if (node.IsSequence()) {
      for (std::size_t i = 0; i < node.size(); ++i) {
        children.emplace_back(node[i], path + "[" + std::to_string(i) + "]");
      }
    } else {
      std::set<std::string> keys;
      for (const auto& kv : node) {
        const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string("?");
        const std::string key_path = path.empty() ? key : path + "." + key;
        if (kv.first.IsScalar() && !keys.insert(key).second) {
          throw InputError(
              file, kv.first.Mark().line + 1, key_path,
              "repeated key (the mapping already has '" + key + "'; only one value may be given)");
        }
        children.emplace_back(kv.second, key_path);
      }
    }
    pending.insert(pending.end(), children.rbegin(), children.rend());
  }
}

ConfigNode ParseYaml(const std::string& text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(file, e.mark.line + 1, "", "YAML syntax: " + e.msg);
  }
  RequireUniqueKeys(root, file);
  return ConfigNode(root, file, "");
}

ConfigNode LoadYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open the file");
  std::stringstream ss;
  ss << in.rdbuf();
  if (ss.str().find_first_not_of(" \t\r\n") == std::string::npos) {
    throw InputError(path, 0, "", "the file is empty");
  }
  return ParseYaml(ss.str(), path);
}

}  // namespace navtwin

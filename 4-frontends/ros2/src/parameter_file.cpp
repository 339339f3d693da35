#include "parameter_file.hpp"

#include <cmath>

#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"
#include "dispel/ros2/graph.hpp"

namespace dispel::ros2 {
namespace {

io::ConfigError bad(const std::string& origin, const char* key, const YAML::Node& v,
                    const std::string& want) {
  return io::ConfigError(origin + ": " + key + " must be " + want + " (got " +
                         io::quote(YAML::Dump(v)) + ")");
}

}  // namespace

ParameterFile::ParameterFile(const std::vector<ParameterText>& files,
                             const std::string& node_name) {
  rest_ = YAML::Node(YAML::NodeType::Map);
  for (const ParameterText& file : files) {
    origin_ += (origin_.empty() ? "" : ", ") + file.origin;
    const std::string& origin = file.origin;
    try {
      const YAML::Node root = YAML::Load(file.text);
      if (!root.IsDefined() || root.IsNull()) continue;
      if (!root.IsMap()) throw io::ConfigError(origin + ": must be a mapping of parameters");
      // ROS 2's layout: blocks of `ros__parameters` by node name.
      bool blocks = false;
      bool ours = false;
      for (const std::string& key : {std::string("/**"), node_name, "/" + node_name}) {
        const YAML::Node block = root[key];
        if (!block.IsDefined() || !block.IsMap() || !block["ros__parameters"].IsDefined()) continue;
        const YAML::Node params = block["ros__parameters"];
        if (!params.IsMap() && !params.IsNull()) {
          throw io::ConfigError(origin + ": " + key + "'s ros__parameters must be a mapping");
        }
        ours = true;
        if (params.IsNull()) continue;
        for (const auto& entry : params)
          rest_[entry.first.as<std::string>()] = YAML::Clone(entry.second);
      }
      for (const auto& entry : root) {
        if (entry.second.IsMap() && entry.second["ros__parameters"].IsDefined()) blocks = true;
      }
      if (blocks && !ours) {
        std::string names;
        for (const auto& entry : root) {
          names += (names.empty() ? "" : ", ") + io::quote(entry.first.as<std::string>());
        }
        throw io::ConfigError(origin + ": has parameters for " + names + ", not for " +
                              io::quote(node_name) + " or /**");
      }
      if (!blocks) {  // The node's parameters at the top level.
        for (const auto& entry : root)
          rest_[entry.first.as<std::string>()] = YAML::Clone(entry.second);
      }
    } catch (const YAML::Exception& e) {
      throw io::ConfigError(origin + ": not YAML (" + io::one_line(e.what()) + ")");
    }
  }
}

YAML::Node ParameterFile::take(const char* key) {
  const YAML::Node& map = rest_;  // Looked up const: a missing key is not made.
  const YAML::Node v = map[key];
  if (!v.IsDefined()) return YAML::Node(YAML::NodeType::Undefined);
  YAML::Node copy = YAML::Clone(v);
  rest_.remove(key);
  return copy;
}

void ParameterFile::text(const char* key, std::string& out) {
  const YAML::Node v = take(key);
  if (!v.IsDefined()) return;
  if (!v.IsScalar()) throw bad(origin_, key, v, "a string");
  out = v.Scalar();
}

void ParameterFile::topic(const char* key, std::string& out) {
  text(key, out);
  if (!out.empty() && out[0] != '/') out = "/" + out;
}

void ParameterFile::boolean(const char* key, bool& out) {
  const YAML::Node v = take(key);
  if (!v.IsDefined()) return;
  if (!v.IsScalar() || !YAML::convert<bool>::decode(v, out)) {
    throw bad(origin_, key, v, "true or false");
  }
}

void ParameterFile::number(const char* key, double& out, double min, const char* want) {
  const YAML::Node v = take(key);
  if (!v.IsDefined()) return;
  double d = 0.0;
  if (!v.IsScalar() || !YAML::convert<double>::decode(v, d) || !std::isfinite(d) || d < min) {
    throw bad(origin_, key, v, want);
  }
  out = d;
}

void ParameterFile::integer(const char* key, int& out, int min, int max) {
  const YAML::Node v = take(key);
  if (!v.IsDefined()) return;
  double d = 0.0;
  const std::string want = "an integer from " + std::to_string(min) + " to " + std::to_string(max);
  if (!v.IsScalar() || !YAML::convert<double>::decode(v, d) || !(d >= min && d <= max) ||
      d != std::floor(d)) {
    throw bad(origin_, key, v, want);
  }
  out = static_cast<int>(d);
}

void ParameterFile::choice(const char* key, std::string& out,
                           const std::vector<std::string>& choices) {
  const YAML::Node v = take(key);
  if (!v.IsDefined()) return;
  std::string want;
  for (std::size_t k = 0; k < choices.size(); ++k) {
    want += (k == 0 ? "" : k + 1 == choices.size() ? " or " : ", ") + choices[k];
  }
  for (const std::string& c : choices) {
    if (v.IsScalar() && v.Scalar() == c) {
      out = c;
      return;
    }
  }
  throw bad(origin_, key, v, want);
}

void ParameterFile::distribution(const char* key, std::string& out) {
  text(key, out);
  if (out.empty()) return;
  try {
    gid_layout_named(out);
  } catch (const DdsError& e) {
    throw io::ConfigError(origin_ + ": " + e.what());
  }
}

std::string ParameterFile::rest_yaml() const {
  return rest_.size() == 0 ? std::string("{}") : YAML::Dump(rest_);
}

std::vector<std::string> ParameterFile::rest_keys() const {
  std::vector<std::string> keys;
  for (const auto& entry : rest_) keys.push_back(entry.first.as<std::string>());
  return keys;
}

}  // namespace dispel::ros2

#pragma once
// A ROS 2 parameter file as dispel-ros2's nodes read it (internal to dispel::ros2): the node's
// mapping (`<node>: ros__parameters:`, "/**", or the file's top level), its own keys taken one by
// one with checks that name the key, and the rest given to the filter's or the fusion's parser.
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "dispel/ros2/parameter_text.hpp"

namespace dispel::ros2 {

class ParameterFile {
 public:
  /// The node's parameters from @p files in order, as rcl reads several `--params-file`: in each,
  /// the "/**" block, then the node's own (`name` or `/name`), a later value replacing an earlier
  /// one; a file with no `ros__parameters` blocks is the node's parameters at its top level.
  /// @throws io::ConfigError: not YAML, not a mapping, or parameters for other nodes only.
  ParameterFile(const std::vector<ParameterText>& files, const std::string& node_name);

  // Each takes its key out of the rest, if there, into @p out; a value of the wrong type or
  // range throws io::ConfigError naming the key, what it must be, and the value.
  void text(const char* key, std::string& out);
  /// A topic: a name without a leading '/' gets one (the nodes have no namespace).
  void topic(const char* key, std::string& out);
  void boolean(const char* key, bool& out);
  void number(const char* key, double& out, double min, const char* want);
  void integer(const char* key, int& out, int min, int max);
  /// One of @p choices.
  void choice(const char* key, std::string& out, const std::vector<std::string>& choices);
  /// ros_distro: empty, or a distribution gid_layout_named() knows.
  void distribution(const char* key, std::string& out);

  /// The keys not taken, as YAML text ("{}" when none).
  std::string rest_yaml() const;
  std::vector<std::string> rest_keys() const;
  const std::string& origin() const { return origin_; }

 private:
  YAML::Node take(const char* key);
  std::string origin_;
  YAML::Node rest_;
};

}  // namespace dispel::ros2

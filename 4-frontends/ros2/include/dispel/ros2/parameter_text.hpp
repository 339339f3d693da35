#pragma once
/// @file
/// A ROS 2 parameter file's text, as dispel-ros2's nodes take them (several, as `--params-file`
/// may be given several times; `-p name:=value` is one more).

#include <string>

namespace dispel::ros2 {

struct ParameterText {
  std::string text;    ///< YAML.
  std::string origin;  ///< Its name in errors: the file's path.
};

}  // namespace dispel::ros2

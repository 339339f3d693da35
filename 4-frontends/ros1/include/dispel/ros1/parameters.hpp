#pragma once
/// @file
/// A node's private ROS parameters as the YAML text that dispel's configuration parser reads
/// (io/config_yaml.hpp), so that every key, check and message is the one of
/// `dispel filter --config`; and the few parameters that belong to the node itself.

#include <xmlrpcpp/XmlRpcValue.h>

#include <set>
#include <stdexcept>
#include <string>

namespace dispel::ros1 {

/// A parameter that cannot be used; what() is one line naming it.
class ParameterError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// YAML (flow style) for a parameter tree: structs become mappings, arrays sequences, strings
/// double-quoted scalars (the parser converts by the field's type, so a number that rosparam kept
/// as a string, "1e-4", still reads as a number), doubles with 17 significant digits.
/// Members whose names are in @p skip are left out at the top level.
/// @throws ParameterError for a value of a type YAML cannot hold here (base64, date and time).
std::string to_yaml(const XmlRpc::XmlRpcValue& tree, const std::set<std::string>& skip = {});

/// The parameters of a node that are not the filter's or the odometry's: read with their types
/// checked, each one remembered so that the rest of the tree can go to the configuration parser.
class NodeParameters {
 public:
  /// @p tree: the node's private namespace (a struct, or invalid when it has no parameters);
  /// @p prefix names them in errors ("~").
  NodeParameters(const XmlRpc::XmlRpcValue& tree, std::string prefix);

  std::string text(const std::string& key, const std::string& fallback);
  /// A string that must be one of @p choices.
  std::string choice(const std::string& key, const std::string& fallback,
                     const std::set<std::string>& choices);
  double number(const std::string& key, double fallback);
  int integer(const std::string& key, int fallback);
  bool boolean(const std::string& key, bool fallback);

  /// Throws ParameterError "<prefix><key> must be <what>, got <value>" when @p ok is false.
  void require(bool ok, const std::string& key, const std::string& what, double value) const;

  /// The keys read so far (for to_yaml()'s skip).
  const std::set<std::string>& keys() const { return keys_; }
  /// The whole tree, or an empty struct.
  const XmlRpc::XmlRpcValue& tree() const { return tree_; }
  /// The names of the top-level members.
  std::set<std::string> members() const;

 private:
  XmlRpc::XmlRpcValue* find(const std::string& key);
  [[noreturn]] void wrong(const std::string& key, const char* what,
                          const XmlRpc::XmlRpcValue& value) const;

  XmlRpc::XmlRpcValue tree_;
  std::string prefix_;
  std::set<std::string> keys_;
};

}  // namespace dispel::ros1

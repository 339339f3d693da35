#pragma once
/// @file
/// Fixed transforms between named frames (a sensor mount read from /tf_static or /tf).

#include <map>
#include <optional>
#include <string>
#include <utility>

#include "dispel/core/pose2.hpp"

namespace dispel::io {

/// Planar transforms between frames, each edge stored once and usable both ways. Frame names are
/// compared without a leading '/' ("/base_link" and "base_link" are one frame).
class FrameTree {
 public:
  /// Sets the pose of @p child in @p parent (replacing an earlier value of the same edge).
  void set(const std::string& parent, const std::string& child, const Pose2& child_in_parent);

  /// The pose of @p target in @p source, through any chain of edges; nullopt if unconnected.
  std::optional<Pose2> lookup(const std::string& source, const std::string& target) const;

  std::size_t edge_count() const { return edges_.size(); }

  static std::string normalise(const std::string& frame);

 private:
  std::map<std::pair<std::string, std::string>, Pose2>
      edges_;  // (parent, child) -> child in parent
};

}  // namespace dispel::io

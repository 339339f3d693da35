#include "dispel/io/frame_tree.hpp"

#include <deque>
#include <set>

namespace dispel::io {

std::string FrameTree::normalise(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

void FrameTree::set(const std::string& parent, const std::string& child,
                    const Pose2& child_in_parent) {
  const std::string p = normalise(parent);
  const std::string c = normalise(child);
  edges_.erase({c, p});  // One direction per pair.
  edges_[{p, c}] = child_in_parent;
}

std::optional<Pose2> FrameTree::lookup(const std::string& source, const std::string& target) const {
  const std::string from = normalise(source);
  const std::string to = normalise(target);
  if (from == to) return Pose2{};
  // Breadth-first search; each frame's pose in `from` is known when it is reached.
  std::map<std::string, Pose2> reached{{from, Pose2{}}};
  std::deque<std::string> queue{from};
  while (!queue.empty()) {
    const std::string frame = queue.front();
    queue.pop_front();
    const Pose2 frame_in_source = reached.at(frame);
    for (const auto& [edge, child_in_parent] : edges_) {
      std::string next;
      Pose2 next_in_frame;
      if (edge.first == frame) {
        next = edge.second;
        next_in_frame = child_in_parent;
      } else if (edge.second == frame) {
        next = edge.first;
        next_in_frame = child_in_parent.inverse();
      } else {
        continue;
      }
      if (reached.count(next) != 0) continue;
      reached[next] = frame_in_source * next_in_frame;
      if (next == to) return reached[next];
      queue.push_back(next);
    }
  }
  return std::nullopt;
}

}  // namespace dispel::io

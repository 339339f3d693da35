#include "dispel/ros2/graph.hpp"

namespace dispel::ros2 {
namespace {

// Little-endian XCDR1, aligned from the end of the encapsulation header.
class CdrOut {
 public:
  CdrOut() : bytes_{0x00, 0x01, 0x00, 0x00} {}
  void align(std::size_t n) {
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
  }
  void u32(std::uint32_t v) {
    align(4);
    for (int k = 0; k < 4; ++k) bytes_.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void string(const std::string& s) {  // The length counts the NUL.
    u32(static_cast<std::uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  void gid(const Guid& g, GidLayout layout) {  // char[N]: bytes, no alignment.
    bytes_.insert(bytes_.end(), g.begin(), g.end());
    if (layout == GidLayout::kHumble) bytes_.insert(bytes_.end(), 8, 0);
  }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<std::uint8_t> bytes_;
};

}  // namespace

GidLayout gid_layout_named(const std::string& distribution) {
  if (distribution == "humble") return GidLayout::kHumble;
  for (const char* later : {"iron", "jazzy", "kilted", "rolling"}) {
    if (distribution == later) return GidLayout::kIron;
  }
  throw DdsError("ros_distro '" + distribution.substr(0, 40) +
                 "' is not humble, iron, jazzy, kilted or rolling");
}

std::vector<std::uint8_t> encode_participant_entities(const Guid& participant,
                                                      const std::vector<NodeEntities>& nodes,
                                                      GidLayout layout) {
  CdrOut out;
  out.gid(participant, layout);
  out.u32(static_cast<std::uint32_t>(nodes.size()));
  for (const NodeEntities& node : nodes) {
    for (const std::string* s : {&node.name_space, &node.name}) {
      if (s->size() > 256) {  // string<=256 in NodeEntitiesInfo.msg.
        throw DdsError("a node name or namespace longer than 256 characters: '" + s->substr(0, 40) +
                       "...'");
      }
    }
    out.string(node.name_space);
    out.string(node.name);
    for (const std::vector<Guid>* gids : {&node.readers, &node.writers}) {
      out.u32(static_cast<std::uint32_t>(gids->size()));
      for (const Guid& g : *gids) out.gid(g, layout);
    }
  }
  return out.take();
}

DdsTopic discovery_topic() {
  return {"ros_discovery_info", "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"};
}

}  // namespace dispel::ros2

#pragma once
// A ROS 1 bag read back with the real bag library, for tests of what dispel wrote: the scans of
// every LaserScan topic and the message count of every topic.
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace dispel::test {

struct BagContents {
  std::map<std::string, std::vector<sensor_msgs::LaserScan>> scans;
  std::map<std::string, std::size_t> count;
};

inline BagContents read_bag(const std::string& path) {
  BagContents c;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  for (const rosbag::MessageInstance& m : view) {
    ++c.count[m.getTopic()];
    if (const auto s = m.instantiate<sensor_msgs::LaserScan>()) c.scans[m.getTopic()].push_back(*s);
  }
  return c;
}

}  // namespace dispel::test

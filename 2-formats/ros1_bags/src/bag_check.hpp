#pragma once
// The record structure of a ROS bag v2.0 checked before the bag library reads it (internal to
// dispel::io_ros1_bags). The bag library trusts every length and offset in a bag: a corrupt one
// made it read outside its buffers (SIGSEGV) or allocate without bound.

#include <string>

namespace dispel::io {

/// Walks every record of the bag at @p path: the file's records (headers read, data seeked past,
/// except for index and chunk-info entries and connection headers), and each chunk's records
/// (decompressed one chunk at a time). Checks every length against what holds it, every index
/// entry against a message record of its chunk, every chunk info against its chunk, the bag
/// header's index position and counts. A file that does not start with "#ROSBAG V2.0\n" is left
/// to the bag library.
/// @throws InputError "<path>: corrupt bag: record at byte N: <what is wrong>"
void check_bag_structure(const std::string& path);

}  // namespace dispel::io

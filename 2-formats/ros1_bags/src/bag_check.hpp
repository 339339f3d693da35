#pragma once
// The record structure of a ROS bag v2.0 checked before the bag library reads it (internal to
// dispel::io_ros1_bags). The bag library trusts every length and offset in a bag: a corrupt one
// made it read outside its buffers (SIGSEGV) or allocate without bound.

#include <cstddef>
#include <cstdint>
#include <string>

#include "dispel/io/recording.hpp"

namespace dispel::io {

/// Walks every record of the bag at @p path: the file's records (headers read, data seeked past,
/// except for index and chunk-info entries and connection headers), and each chunk's records
/// (decompressed one chunk at a time). Checks every length against what holds it, every index
/// entry against a message record of its chunk, every chunk info against its chunk, the bag
/// header's index position and counts. A bag of format 1.2 is refused (the bag library reads it
/// without checking a length); a file that is not a bag is left to the bag library to name.
/// @throws InputError "<path>: corrupt bag: record at byte N: <what is wrong>", "<path>: a ROS
///         bag of format 1.2 (before 2010) is not read; convert it ..."
void check_bag_structure(const std::string& path);

/// Checks the lengths inside the serialised message @p data (@p size bytes) of a kind dispel
/// decodes, before the ROS deserialiser reads it: that deserialiser sizes an array by its length
/// field before it checks that the message holds it (a length of 2^32 - 1 floats allocated
/// 16 GiB). Every string and array must fit in what is left of the message.
/// @throws InputError "<path>: corrupt bag: message at <time> on <topic> (<type>): an array of
///         N 4-byte values runs past the end of the message (M bytes left)"
void check_message_lengths(const std::string& path, const std::string& topic, Stamp time,
                           MessageKind kind, const std::uint8_t* data, std::size_t size);

}  // namespace dispel::io

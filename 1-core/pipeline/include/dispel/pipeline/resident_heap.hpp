#pragma once
/// @file
/// Heap memory made resident before the first scan, so that no scan pays for memory the process
/// touches for the first time (a real-time practice: prefault at start-up, never give back).

#include <cstddef>

namespace dispel::pipeline {

/// What the programs that filter scans make resident at start (`dispel filter`'s default, the
/// ROS 1 and ROS 2 filter nodes).
inline constexpr std::size_t kDefaultResidentHeapBytes = std::size_t{16} << 20;

/// What reserve_resident_heap() did.
struct ResidentHeap {
  bool reserved = false;  ///< false: the allocator is not glibc's (or is a sanitizer's).
  std::size_t bytes = 0;  ///< Heap touched and kept.
};

/// Makes @p bytes of heap resident for the whole process and keeps it so: every thread allocates
/// from one arena (glibc's main one), freed memory is never returned to the system, blocks up to
/// 1 MB come from that heap (larger ones are mapped on their own, as the filter's free-space
/// window, which the filter fills when it allocates it), and @p bytes are allocated, written and
/// freed once. Call it once, at the start of a program that filters scans, before its threads
/// start. Without it, a filter's first scans took 2-4 times a later scan's time on this
/// project's machine (10-14 µs for each 4 KB page touched the first time; docs/benchmarks.md).
/// A process-wide setting: the libraries never call it on their own. 0 bytes: does nothing.
ResidentHeap reserve_resident_heap(std::size_t bytes);

}  // namespace dispel::pipeline

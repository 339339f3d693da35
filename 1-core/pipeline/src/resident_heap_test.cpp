#include "dispel/pipeline/resident_heap.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdlib>
#include <vector>

namespace dispel::pipeline {
namespace {

long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// Allocates 8 MB in blocks the size a filter's buffers have, writes every page, frees them;
// returns the page faults that took.
long faults_of_fresh_buffers() {
  constexpr std::size_t kBlock = 16 << 10, kBlocks = 512;  // 8 MB
  std::vector<void*> blocks(kBlocks);
  const long before = minor_faults();
  for (void*& block : blocks) {
    block = std::malloc(kBlock);
    auto* bytes = static_cast<volatile unsigned char*>(block);
    for (std::size_t at = 0; at < kBlock; at += 4096) bytes[at] = 1;
  }
  const long faults = minor_faults() - before;
  for (void* block : blocks) std::free(block);
  return faults;
}

TEST(ResidentHeap, BuffersAllocatedAfterItTouchNoNewPage) {
  // First without it: the process's heap gives memory back when it is freed (glibc's default),
  // so fresh buffers fault their pages in, each time.
  const long without = faults_of_fresh_buffers();
  const ResidentHeap heap = reserve_resident_heap(std::size_t{32} << 20);
  if (!heap.reserved) GTEST_SKIP() << "not glibc's allocator (a sanitizer's): nothing to reserve";
  EXPECT_EQ(heap.bytes, std::size_t{32} << 20);
  const long with = faults_of_fresh_buffers();
  const long again = faults_of_fresh_buffers();
  // 8 MB of 4 KB pages is 2048 pages; a few faults may come from elsewhere (the stack).
  EXPECT_GT(without, 1000) << "the baseline did not fault: this test cannot tell";
  EXPECT_LT(with, 32);
  EXPECT_LT(again, 32);
}

TEST(ResidentHeap, ZeroBytesChangesNothing) {
  const ResidentHeap heap = reserve_resident_heap(0);
  EXPECT_FALSE(heap.reserved);
  EXPECT_EQ(heap.bytes, 0U);
}

}  // namespace
}  // namespace dispel::pipeline

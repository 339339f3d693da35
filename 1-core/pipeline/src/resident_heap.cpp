#include "dispel/pipeline/resident_heap.hpp"

#include <cstdlib>
#include <vector>

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#include <malloc.h>
#define DISPEL_GLIBC_MALLOC 1
#endif

namespace dispel::pipeline {

ResidentHeap reserve_resident_heap(std::size_t bytes) {
  ResidentHeap result;
#ifdef DISPEL_GLIBC_MALLOC
  if (bytes == 0) return result;
  constexpr std::size_t kBlock = std::size_t{256} << 10;  // Under the mapping threshold below.
  constexpr int kMapThreshold = 1 << 20;
  constexpr std::size_t kPage = 4096;  // The smallest page; a larger one is written more often.
  // Settings first: a freed block must stay in the heap (trim threshold above anything the
  // process frees), and come from the arena every thread uses.
  if (mallopt(M_ARENA_MAX, 1) != 1 || mallopt(M_MMAP_THRESHOLD, kMapThreshold) != 1 ||
      mallopt(M_TRIM_THRESHOLD, 1 << 30) != 1) {
    return result;
  }
  std::vector<void*> blocks;
  blocks.reserve(bytes / kBlock + 1);
  for (std::size_t done = 0; done < bytes; done += kBlock) {
    void* block = std::malloc(kBlock);
    if (block == nullptr) break;  // Less than asked: what was touched stays resident.
    // One write per page brings it in (through volatile: a store to memory freed right after
    // may otherwise be left out by the compiler).
    auto* bytes_of = static_cast<volatile unsigned char*>(block);
    for (std::size_t at = 0; at < kBlock; at += kPage) bytes_of[at] = 0;
    blocks.push_back(block);
  }
  for (void* block : blocks) std::free(block);
  result.reserved = true;
  result.bytes = blocks.size() * kBlock;
#else
  static_cast<void>(bytes);
#endif
  return result;
}

}  // namespace dispel::pipeline

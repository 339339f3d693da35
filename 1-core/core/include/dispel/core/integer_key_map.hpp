#pragma once
/// @file
/// A map from 64-bit integer keys to values, for lookups in a hot loop: the values in one array,
/// a power-of-two table of (key, index) slots with linear probing beside it, kept at most half
/// full. A lookup hashes by one multiplication and reads one slot in the common case, where
/// std::unordered_map divides by a prime and follows a node pointer.
///
/// A pointer or reference to a value stays valid until the next insertion or erase_if(). The
/// order of values is the order of insertion, until erase_if() moves them.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace dispel {

template <typename T>
class IntegerKeyMap {
 public:
  using Key = std::uint64_t;

  /// The value of @p key, or nullptr.
  T* find(Key key) {
    const std::int32_t index = index_of(key);
    return index < 0 ? nullptr : &values_[static_cast<std::size_t>(index)].second;
  }
  const T* find(Key key) const {
    const std::int32_t index = index_of(key);
    return index < 0 ? nullptr : &values_[static_cast<std::size_t>(index)].second;
  }

  /// The value of @p key, value-initialised first if there is none.
  T& operator[](Key key) {
    if (slots_.empty()) rehash(kMinSlots);
    std::size_t s = slot_of(key);
    while (slots_[s].index >= 0) {
      if (slots_[s].key == key) return values_[static_cast<std::size_t>(slots_[s].index)].second;
      s = (s + 1) & mask_;
    }
    if (2 * (values_.size() + 1) > slots_.size()) {
      values_.emplace_back(key, T{});
      rehash(2 * slots_.size());
      return values_.back().second;
    }
    slots_[s] = {key, static_cast<std::int32_t>(values_.size())};
    values_.emplace_back(key, T{});
    return values_.back().second;
  }

  /// Erases every value for which @p erase(key, value) is true.
  template <typename Predicate>
  void erase_if(Predicate erase) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < values_.size(); ++i) {
      if (erase(values_[i].first, static_cast<const T&>(values_[i].second))) continue;
      if (kept != i) values_[kept] = std::move(values_[i]);
      ++kept;
    }
    if (kept == values_.size()) return;
    values_.resize(kept);
    rehash(slots_.size());
  }

  std::size_t size() const { return values_.size(); }
  bool empty() const { return values_.empty(); }
  void clear() {
    values_.clear();
    slots_.clear();
    mask_ = 0;
  }

 private:
  struct Slot {
    Key key = 0;
    std::int32_t index = -1;  // Into values_; -1: empty.
  };
  static constexpr std::size_t kMinSlots = 64;

  std::size_t slot_of(Key key) const {
    // Fibonacci hashing: the high bits of the product mix every bit of the key.
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> shift_) & mask_;
  }
  std::int32_t index_of(Key key) const {
    if (slots_.empty()) return -1;
    for (std::size_t s = slot_of(key);; s = (s + 1) & mask_) {
      const Slot& slot = slots_[s];
      if (slot.index < 0 || slot.key == key) return slot.index;
    }
  }
  // Rebuilds the slots for values_ in a table of at least @p slots (a power of two), doubled
  // until it is at most half full.
  void rehash(std::size_t slots) {
    while (2 * values_.size() > slots) slots *= 2;
    slots_.assign(slots, Slot{});
    mask_ = slots - 1;
    int bits = 0;
    while ((std::size_t{1} << bits) < slots) ++bits;
    shift_ = 64 - bits;
    for (std::size_t i = 0; i < values_.size(); ++i) {
      std::size_t s = slot_of(values_[i].first);
      while (slots_[s].index >= 0) s = (s + 1) & mask_;
      slots_[s] = {values_[i].first, static_cast<std::int32_t>(i)};
    }
  }

  std::vector<std::pair<Key, T>> values_;
  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  int shift_ = 64;
};

}  // namespace dispel

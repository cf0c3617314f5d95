// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// FlatIndex: an open-addressing hash table from a 64-bit key to a 32-bit slot number.
//
// It is the top level of the hashed map (brick key -> brick slot) and of per-scan scratch
// tables. Linear probing over a power-of-two table, load factor <= 1/2, no erase (both users
// only grow or clear), and clear() keeps the capacity so a warmed-up scan allocates nothing.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "huge_pages.hpp"

namespace knnocc::detail {

class FlatIndex {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  ///< never a valid key
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  /// Slot stored for `key`, or kNone.
  std::uint32_t find(std::uint64_t key) const {
    if (keys_.empty()) return kNone;
    for (std::size_t i = bucket(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return values_[i];
      if (keys_[i] == kEmpty) return kNone;
    }
  }

  /// Slot stored for `key`; when absent, stores `value_if_new` and returns it. `inserted` tells.
  std::uint32_t find_or_insert(std::uint64_t key, std::uint32_t value_if_new, bool& inserted) {
    if (2 * (size_ + 1) > keys_.size()) grow();
    for (std::size_t i = bucket(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) {
        inserted = false;
        return values_[i];
      }
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        values_[i] = value_if_new;
        ++size_;
        inserted = true;
        return value_if_new;
      }
    }
  }

  /// Forgets every key but keeps the table's memory.
  void clear() {
    if (size_ == 0) return;
    std::fill(keys_.begin(), keys_.end(), kEmpty);
    size_ = 0;
  }

  /// Forgets every key and releases the memory.
  void reset() {
    keys_.clear();
    keys_.shrink_to_fit();
    values_.clear();
    values_.shrink_to_fit();
    size_ = 0;
    mask_ = 0;
  }

  /// Room for n keys without growing.
  void reserve(std::size_t n) {
    std::size_t cap = keys_.empty() ? 64 : keys_.size();
    while (2 * n > cap) cap *= 2;
    if (cap > keys_.size()) grow(cap);
  }

  std::size_t memory_usage() const {
    return keys_.capacity() * sizeof(std::uint64_t) + values_.capacity() * sizeof(std::uint32_t);
  }
  /// How much memory_usage() grows to hold n keys (n = size() + 1: the next new key).
  std::size_t growth_bytes(std::size_t n) const {
    std::size_t cap = keys_.empty() ? 64 : keys_.size();
    while (2 * n > cap) cap *= 2;
    return cap <= keys_.size()
               ? 0
               : (cap - keys_.size()) * (sizeof(std::uint64_t) + sizeof(std::uint32_t));
  }

 private:
  std::size_t bucket(std::uint64_t key) const {
    // splitmix64 finaliser: brick keys differ in few low bits per axis, so mix them all.
    key ^= key >> 30;
    key *= 0xbf58476d1ce4e5b9ULL;
    key ^= key >> 27;
    key *= 0x94d049bb133111ebULL;
    key ^= key >> 31;
    return static_cast<std::size_t>(key) & mask_;
  }

  void grow() { grow(keys_.empty() ? 64 : 2 * keys_.size()); }
  void grow(std::size_t cap) {
    BigVector<std::uint64_t> old_keys(cap, kEmpty);
    BigVector<std::uint32_t> old_values(cap);
    old_keys.swap(keys_);
    old_values.swap(values_);
    mask_ = cap - 1;
    for (std::size_t j = 0; j < old_keys.size(); ++j) {
      if (old_keys[j] == kEmpty) continue;
      std::size_t i = bucket(old_keys[j]);
      while (keys_[i] != kEmpty) i = (i + 1) & mask_;
      keys_[i] = old_keys[j];
      values_[i] = old_values[j];
    }
  }

  BigVector<std::uint64_t> keys_;  // every page is touched: large tables take huge pages
  BigVector<std::uint32_t> values_;
  std::size_t size_ = 0;
  std::size_t mask_ = 0;
};

}  // namespace knnocc::detail

// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// AppendBuffer: a growable array of trivially copyable elements for per-point loops.
//
// std::vector::push_back inlined into ScanInserter's collect loop only sometimes (GCC kept a
// call per point once the loop body grew); here the loop asks for room for all its elements
// first (room_for) and then appends with plain stores through a pointer, with no capacity test
// per element. Storage keeps its size between uses (clear() resets the count, not the memory)
// and comes from big_alloc, so large buffers take huge pages.

#include <cstddef>
#include <type_traits>

#include "../../core/detail/huge_pages.hpp"

namespace knnocc::detail {

template <class T>
class AppendBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "elements are moved with plain stores");

 public:
  std::size_t size() const { return size_; }
  T* data() { return storage_.data(); }
  const T* data() const { return storage_.data(); }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size_; }
  const T& operator[](std::size_t i) const { return storage_[i]; }

  std::size_t capacity_bytes() const { return storage_.capacity() * sizeof(T); }
  void clear() { size_ = 0; }
  /// Room for n elements in all (grown with an eighth to spare: buffers of slowly growing scans
  /// do not each take a fresh block).
  void reserve(std::size_t n) {
    if (storage_.size() < n) storage_.resize(n + n / 8);
  }
  /// Room for n more elements; returns where the next one goes. Write them through the pointer,
  /// then set_end() to where writing stopped.
  T* room_for(std::size_t n) {
    reserve(size_ + n);
    return data() + size_;
  }
  void set_end(const T* end) { size_ = static_cast<std::size_t>(end - data()); }

 private:
  BigVector<T> storage_;  // its size is the capacity; the first size_ elements are in use
  std::size_t size_ = 0;
};

}  // namespace knnocc::detail

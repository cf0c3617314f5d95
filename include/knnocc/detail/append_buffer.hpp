#pragma once
// AppendBuffer: a growable array of trivially copyable elements for per-point loops.
//
// std::vector::push_back inlined into ScanInserter's collect loop only sometimes (GCC kept a
// call per point once the loop body grew); here an append is a capacity test and a store, and
// only the rare growth is a call. Storage keeps its size between uses (clear() resets the count,
// not the memory) and comes from big_alloc, so large buffers take huge pages.

#include <cstddef>
#include <type_traits>

#include "../core/config.hpp"
#include "huge_pages.hpp"

namespace knnocc::detail {

template <class T>
class AppendBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "elements are moved with plain stores");

 public:
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* data() { return storage_.data(); }
  const T* data() const { return storage_.data(); }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size_; }
  const T& operator[](std::size_t i) const { return storage_[i]; }

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
  /// Appends an element and returns it: whatever an earlier use left there, so set every field.
  KNNOCC_ALWAYS_INLINE T& append() {
    if (size_ == storage_.size()) grow();
    return storage_[size_++];
  }
  KNNOCC_ALWAYS_INLINE void push_back(const T& v) { append() = v; }

 private:
  KNNOCC_NOINLINE void grow() { storage_.resize(storage_.empty() ? 64 : 2 * storage_.size()); }

  BigVector<T> storage_;  // its size is the capacity; the first size_ elements are in use
  std::size_t size_ = 0;
};

}  // namespace knnocc::detail

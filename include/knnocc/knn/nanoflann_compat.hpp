// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The one place that knows nanoflann's version differences (Debian 12's 1.4.3, which reports
// itself as 1.4.2 = 0x142, and 1.5+):
//   - SearchParams was renamed SearchParameters in 1.5 (and gained a default argument);
//   - 1.5 static_casts distances and indices to RESULTSET::DistanceType / IndexType, so our own
//     result sets declare both;
//   - the dynamic adaptor's index type parameter defaults to size_t (1.4) or uint32_t (1.5);
//     we always pass it explicitly.
// Everything else talks to the dynamic index only through findNeighbors with knnocc's result
// sets (knn/point_index.hpp).

// nanoflann 1.4.3's dynamic adaptor copies sub-trees whose bounding box is not yet set; GCC's
// -Wmaybe-uninitialized reports that from inside the header, whatever the include path kind.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "../core/config.hpp"
#if !KNNOCC_HAS_EXCEPTIONS
// Built with -fno-exceptions: nanoflann's few `throw`s (index misuse, allocation failure) become
// abort(). GCC rejects a throw expression even in code that is never called, so `throw` is
// redefined for nanoflann's text only: every standard header it (1.4.3 or 1.5.x) includes is
// included first, unaffected. Redefining a keyword is outside standard C++ (GCC and Clang accept
// it); it happens only in -fno-exceptions builds. A nanoflann that includes a standard header not
// listed here would need it added (noexcept.smoke fails to build otherwise).
#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <future>
#include <istream>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <ostream>
#include <stdexcept>
#include <thread>
#include <type_traits>
#include <unordered_set>
#include <utility>
#include <vector>
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wkeyword-macro"
#endif
#define throw std::abort(),
#include <nanoflann.hpp>
#undef throw
#if defined(__clang__)
#pragma clang diagnostic pop
#endif
#else
#include <nanoflann.hpp>
#endif
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace knnocc::detail {

#if NANOFLANN_VERSION >= 0x150
using NanoflannSearchParams = nanoflann::SearchParameters;
#else
using NanoflannSearchParams = nanoflann::SearchParams;
#endif

inline constexpr int kNanoflannVersion = NANOFLANN_VERSION;

}  // namespace knnocc::detail

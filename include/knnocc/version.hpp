// SPDX-License-Identifier: BSD-3-Clause
// knnocc version information.
//
// The top-level CMakeLists.txt parses the three KNNOCC_VERSION_* macros below
// to set the project version, so keep their "#define NAME <number>" form.
#ifndef KNNOCC_VERSION_HPP
#define KNNOCC_VERSION_HPP

#define KNNOCC_VERSION_MAJOR 0
#define KNNOCC_VERSION_MINOR 1
#define KNNOCC_VERSION_PATCH 0
#define KNNOCC_VERSION_STRING "0.1.0"

namespace knnocc {

/// Library version as "MAJOR.MINOR.PATCH".
inline constexpr const char* version_string = KNNOCC_VERSION_STRING;

}  // namespace knnocc

#endif  // KNNOCC_VERSION_HPP

#pragma once
// A command's output files, checked before any work: each named (not ""), in an existing,
// writable folder, not a folder itself, not a read-only file, and no two the same file; temporaries
// of them that a killed run left behind are removed (io::remove_stale_temporaries). Writing them
// then happens in an io::CommitGroup, so a failure leaves every target as it was.

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/error.hpp>

#include "args.hpp"

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

namespace knnocc::cli {

/// (option, path) of each output a command was asked to write.
using OutputList = std::vector<std::pair<std::string, std::string>>;

/// The given options among `options` with their values.
inline OutputList requested_outputs(const Args& args, const std::vector<std::string>& options) {
  OutputList out;
  for (const auto& o : options)
    if (args.has(o)) out.emplace_back(o, args.str(o));
  return out;
}

namespace detail {
/// The file a path names, for comparing two outputs (symbolic links and "a/../b" resolved).
inline std::filesystem::path output_identity(const std::string& path) {
  std::error_code ec;
  auto p = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec);
  return ec ? std::filesystem::path(path).lexically_normal() : p;
}
}  // namespace detail

/// Throws UsageError (bad names, one file given twice) or io::Error (a folder that is missing
/// or not writable, a target that is a folder or a read-only file) naming the output; a device or
/// FIFO is accepted.
inline void check_outputs(const OutputList& outputs) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, fs::path>> seen;
  for (const auto& [option, path] : outputs) {
    if (path.empty()) throw UsageError(option + " needs a file name, got ''");
    std::error_code ec;
    const auto st = fs::status(path, ec);
    if (st.type() == fs::file_type::directory)
      throw io::Error(path, "is a folder; " + option + " needs a file name");
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec))
      throw io::Error(path, "folder '" + dir.string() + "' does not exist (" + option + ")");
#if defined(__unix__) || defined(__APPLE__)
    const bool special = fs::exists(st) && !fs::is_regular_file(st);
    if (!special && ::access(dir.c_str(), W_OK | X_OK) != 0)
      throw io::Error(path, "folder '" + dir.string() + "' is not writable (" + option + ")");
    if (special && ::access(path.c_str(), W_OK) != 0)
      throw io::Error(path, "is not writable (" + option + ")");
    // A read-only file is kept, as cp and install keep it: replacing it takes a deliberate step.
    // Root may write any file, so for root the mode's write bits decide.
    constexpr auto kAnyWrite =
        fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write;
    if (fs::is_regular_file(st) &&
        (::access(path.c_str(), W_OK) != 0 || (st.permissions() & kAnyWrite) == fs::perms::none))
      throw io::Error(path, "is read-only (" + option +
                                "); nothing was written: make it writable (chmod u+w) or remove "
                                "it to replace it");
#endif
    const fs::path id = detail::output_identity(path);
    for (const auto& [other, other_id] : seen) {
      bool same = id == other_id;
      if (!same && fs::exists(id, ec) && fs::exists(other_id, ec))
        same = fs::equivalent(id, other_id, ec) && !ec;
      // Writing one device twice (e.g. /dev/null as two sinks) is harmless.
      if (same && !(fs::exists(st) && !fs::is_regular_file(st)))
        throw UsageError(option + " and " + other + " name the same file '" + path + "'");
    }
    seen.emplace_back(option, id);
  }
  for (const auto& output : outputs) io::remove_stale_temporaries(output.second);
}

/// Throws io::Error naming standard output when anything written to it was lost (e.g. a full
/// disk or /dev/full); the command then exits 2.
inline void check_stdout() {
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    const int err = errno;
    throw io::Error("standard output",
                    err ? "write failed: " + io::detail::errno_text(err) : "write failed");
  }
}

}  // namespace knnocc::cli

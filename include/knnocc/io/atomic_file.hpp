#pragma once
// AtomicFile: how every knnocc output is written (failures throw io::Error naming the target).

#include <cerrno>
#include <cstdio>
#include <string>
#include <system_error>

#include "error.hpp"

namespace knnocc::io {

namespace detail {
inline std::string errno_text(int err) { return std::generic_category().message(err); }
}  // namespace detail

// Writes to "<path>.tmp" in the same directory and renames over <path> on commit(), so readers
// never see a half-written file. Without commit() (e.g. an exception) the temp file is removed.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path) : path_(path), tmp_(path + ".tmp") {
    file_ = std::fopen(tmp_.c_str(), "wb");
    if (!file_) {
      throw Error(path_,
                  "cannot create temporary file '" + tmp_ + "': " + detail::errno_text(errno));
    }
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() {
    if (file_) std::fclose(file_);
    if (!committed_) std::remove(tmp_.c_str());
  }

  void write(const char* bytes, std::size_t n) {
    if (n != 0 && std::fwrite(bytes, 1, n, file_) != n) fail("write failed");
  }
  void write(const std::string& s) { write(s.data(), s.size()); }

  void commit() {
    if (!file_) throw Error(path_, "internal: AtomicFile committed twice");
    std::FILE* f = file_;
    file_ = nullptr;
    const bool flushed = std::fflush(f) == 0;
    const int flush_err = errno;
    if (std::fclose(f) != 0 || !flushed) fail_errno("write failed", flushed ? errno : flush_err);
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
      fail_errno("cannot rename '" + tmp_ + "' to the target", errno);
    }
    committed_ = true;
  }

 private:
  [[noreturn]] void fail(const std::string& what) { fail_errno(what, errno); }
  [[noreturn]] void fail_errno(const std::string& what, int err) {
    throw Error(path_, what + (err ? ": " + detail::errno_text(err) : std::string()));
  }

  std::string path_;
  std::string tmp_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

}  // namespace knnocc::io

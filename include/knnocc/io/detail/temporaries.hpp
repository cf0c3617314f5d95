// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The temporary files (and staging folders) knnocc is writing right now, so a SIGINT/SIGTERM
// handler can remove them before the process dies (io::remove_temporaries_on_signal()).
//
// A fixed table of atomic pointers: registering and unregistering take no lock, and the handler
// only loads pointers and calls unlink()/rmdir() (async-signal-safe). A path that does not fit in
// the table (more than kMaxTemporaries at once) is simply not registered: it is still removed by
// its owner on every normal or exceptional exit, only not on a signal.

#include <atomic>
#include <csignal>
#include <cstddef>
#include <cstdio>
#include <cstring>

#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__linux__)
#include <sys/syscall.h>
#endif
#define KNNOCC_POSIX_FILES 1
#else
#define KNNOCC_POSIX_FILES 0
#endif

namespace knnocc::io::detail {

inline constexpr std::size_t kMaxTemporaries = 256;

/// One slot per live temporary: its path (owned by the registrant) or null; `dir` marks a
/// staging folder, removed with its contents.
struct TemporarySlot {
  std::atomic<const char*> path;
  std::atomic<bool> dir;
};
inline TemporarySlot temporary_slots[kMaxTemporaries];

/// Marks a slot taken while its `dir` flag is set, before its path is published.
inline const char* const kClaimedSlot = "";

/// Registers `path` (which must stay valid until unregister_temporary); returns the slot or -1.
inline int register_temporary(const char* path, bool is_dir = false) noexcept {
  for (std::size_t i = 0; i < kMaxTemporaries; ++i) {
    const char* expected = nullptr;
    if (temporary_slots[i].path.compare_exchange_strong(expected, kClaimedSlot)) {
      temporary_slots[i].dir.store(is_dir);
      temporary_slots[i].path.store(path);
      return static_cast<int>(i);
    }
  }
  return -1;
}
inline void unregister_temporary(int slot) noexcept {
  if (slot >= 0) temporary_slots[slot].path.store(nullptr);
}

#if KNNOCC_POSIX_FILES
/// Removes a staging folder and what it holds (depth bounded: the tool's folder outputs are at
/// most three levels deep). Async-signal-safe on Linux; elsewhere only files are removed here.
inline void remove_tree_signal_safe(int parent_fd, const char* name, int depth) noexcept {
  if (unlinkat(parent_fd, name, 0) == 0 || depth > 4) return;
  const int fd = openat(parent_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW);
  if (fd < 0) return;
#if defined(__linux__)
  // getdents64 straight from the kernel into a buffer on the stack: unlike fdopendir/readdir it
  // allocates nothing, so it is safe in a handler that interrupted malloc. Entries are removed
  // while the folder is read, so it is read again from the start until nothing is left.
  alignas(8) char buf[2048];
  for (int pass = 0; pass < 64; ++pass) {
    lseek(fd, 0, SEEK_SET);
    bool removed = false;
    for (;;) {
      const long n = syscall(SYS_getdents64, fd, buf, sizeof buf);
      if (n <= 0) break;
      for (long off = 0; off < n;) {
        unsigned short reclen = 0;  // struct linux_dirent64: ino 8, off 8, reclen 2, type 1, name
        std::memcpy(&reclen, buf + off + 16, sizeof reclen);
        const char* entry = buf + off + 19;
        off += reclen;
        if (entry[0] == '.' && (entry[1] == 0 || (entry[1] == '.' && entry[2] == 0))) continue;
        remove_tree_signal_safe(fd, entry, depth + 1);
        removed = true;
      }
    }
    if (!removed) break;
  }
#endif
  close(fd);
  unlinkat(parent_fd, name, AT_REMOVEDIR);
}
#endif

inline void remove_registered_temporaries() noexcept {
  for (auto& slot : temporary_slots) {
    const char* p = slot.path.load();
    if (!p || p == kClaimedSlot) continue;
#if KNNOCC_POSIX_FILES
    if (slot.dir.load())
      remove_tree_signal_safe(AT_FDCWD, p, 0);
    else
      unlink(p);
#else
    std::remove(p);
#endif
  }
}

inline void temporaries_signal_handler(int sig) {
  remove_registered_temporaries();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace knnocc::io::detail

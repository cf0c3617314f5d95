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

#if defined(__unix__) || defined(__APPLE__)
#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
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
/// most three levels deep).
inline void remove_tree_signal_safe(int parent_fd, const char* name, int depth) noexcept {
  if (unlinkat(parent_fd, name, 0) == 0 || depth > 4) return;
  const int fd = openat(parent_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW);
  if (fd < 0) return;
  // fdopendir/readdir may allocate; a handler has nothing better on POSIX. They are used only
  // after a fatal signal, when the process is about to die anyway.
  if (DIR* d = fdopendir(dup(fd))) {
    while (const dirent* e = readdir(d)) {
      const char* n = e->d_name;
      if (n[0] == '.' && (n[1] == 0 || (n[1] == '.' && n[2] == 0))) continue;
      remove_tree_signal_safe(fd, n, depth + 1);
    }
    closedir(d);
  }
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

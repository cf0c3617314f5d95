// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// AtomicFile: how every knnocc output is written (failures throw io::Error naming the target).
// CommitGroup: several outputs committed as a set; StagingDir: a folder output built aside.

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "detail/temporaries.hpp"
#include "error.hpp"

namespace knnocc::io {

namespace detail {
inline std::string errno_text(int err) { return std::generic_category().message(err); }

/// Where the temporary of `target` goes: "<dir>/<name>.tmp-XXXXXX" (the name shortened so the
/// whole stays within a file-name limit of 255 bytes).
inline std::string temporary_template(const std::string& target) {
  const std::filesystem::path p(target);
  std::string name = p.filename().string();
  if (name.size() > 200) name.resize(200);
  const std::filesystem::path dir = p.parent_path();
  return (dir.empty() ? std::string() : dir.string() + "/") + name + ".tmp-XXXXXX";
}

#if KNNOCC_POSIX_FILES
/// The process's umask, read without changing it where /proc says it.
inline mode_t process_umask() {
  static const mode_t mask = [] {
    if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
      char line[256];
      unsigned m = 0;
      while (std::fgets(line, sizeof line, f)) {
        if (std::sscanf(line, "Umask: %o", &m) == 1) {
          std::fclose(f);
          return static_cast<mode_t>(m);
        }
      }
      std::fclose(f);
    }
    const mode_t m = ::umask(022);
    ::umask(m);
    return m;
  }();
  return mask;
}
/// The permission bits a newly created file would get (0666 minus the umask).
inline mode_t new_file_mode() { return static_cast<mode_t>(0666 & ~process_umask()); }
/// The permission bits mkdir would give a new folder (0777 minus the umask).
inline mode_t new_folder_mode() { return static_cast<mode_t>(0777 & ~process_umask()); }
#endif

// A temporary is locked (flock) from its creation until it is renamed or removed, so that
// remove_stale_temporaries() can tell a killed writer's file from a live one.
inline int lock_temporary(int fd) noexcept {
#if KNNOCC_POSIX_FILES
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) return -1;
  return ::fcntl(fd, F_DUPFD_CLOEXEC, 0);  // shares the lock, which outlives the FILE that
                                           // closes fd; not inherited by child processes
#else
  (void)fd;
  return -1;
#endif
}
inline void release_lock(int& lock) noexcept {
#if KNNOCC_POSIX_FILES
  if (lock >= 0) ::close(lock);
#endif
  lock = -1;
}

/// The file in a StagingDir's folder, from its creation to its commit, that tells
/// remove_stale_temporaries() the folder is a staging folder and not a user's.
inline constexpr const char* kStagingMarker = ".knnocc-staging";

class CommitGroupBase;
inline CommitGroupBase*& current_group() {
  thread_local CommitGroupBase* group = nullptr;
  return group;
}

/// A closed temporary waiting for its rename; removes it (and its signal registration) unless
/// renamed. Holds the temporary's lock (see AtomicFile) until then.
struct PendingFile {
  std::unique_ptr<std::string> tmp;  // stable c_str() for the signal registry
  std::string target;
  int slot = -1;
  int lock = -1;  // a descriptor of the temporary holding its flock, or -1
  PendingFile() = default;
  PendingFile(PendingFile&& o) noexcept
      : tmp(std::move(o.tmp)),
        target(std::move(o.target)),
        slot(std::exchange(o.slot, -1)),
        lock(std::exchange(o.lock, -1)) {}
  PendingFile& operator=(PendingFile&&) = delete;
  ~PendingFile() { discard(); }
  void discard() noexcept {
    if (tmp) std::remove(tmp->c_str());
    release();
  }
  void release() noexcept {
    unregister_temporary(std::exchange(slot, -1));
    release_lock(lock);
    tmp.reset();
  }
  void rename() {
    if (std::rename(tmp->c_str(), target.c_str()) != 0) {
      const int err = errno;
      throw Error(target, "cannot rename '" + *tmp + "' to the target: " + errno_text(err), err);
    }
    release();
  }
};

class CommitGroupBase {
 public:
  void defer(PendingFile&& f) { pending_.push_back(std::move(f)); }

 protected:
  std::vector<PendingFile> pending_;
};
}  // namespace detail

/// Removes every temporary knnocc is writing when SIGINT, SIGTERM, SIGHUP or SIGPIPE (a closed
/// pipe on stdout or stderr) arrives, then dies of the signal as it would have (a signal the
/// process ignores stays ignored). For programs: the library never installs it by itself.
inline void remove_temporaries_on_signal() {
  for (int sig : {SIGINT, SIGTERM
#ifdef SIGHUP
                  ,
                  SIGHUP
#endif
#ifdef SIGPIPE
                  ,
                  SIGPIPE
#endif
       }) {
    auto old = std::signal(sig, detail::temporaries_signal_handler);
    if (old == SIG_IGN) std::signal(sig, SIG_IGN);
  }
}

/// Writes to a new, uniquely named temporary file beside `path` (created exclusively, so a
/// user's file is never taken over and concurrent writers of one path never share a file) and
/// renames it over `path` on commit(): readers never see a half-written file. Without commit()
/// (e.g. an exception) the temporary is removed. A target that exists and is not a regular file
/// (a device such as /dev/null, a FIFO) is written directly, never replaced; a symbolic link is
/// followed, so the file it names is replaced and the link stays. A new file gets the usual
/// permissions (0666 minus the umask); a replaced file keeps its own.
/// While a CommitGroup is open on the thread, commit() only closes the file; the group renames.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path) : path_(path) {
    if (path.empty()) throw Error(path, "empty output file name");
#if KNNOCC_POSIX_FILES
    std::string target = path;
    struct stat st;
    mode_t mode = detail::new_file_mode();
    if (::stat(path.c_str(), &st) == 0) {
      if (S_ISDIR(st.st_mode)) throw Error(path_, "is a directory");
      if (!S_ISREG(st.st_mode)) {  // device, FIFO, socket: write in place
        file_ = std::fopen(path.c_str(), "wb");
        if (!file_) fail("cannot open for writing");
        direct_ = true;
        return;
      }
      mode = st.st_mode & 07777;
      struct stat lst;
      if (::lstat(path.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
        std::error_code ec;
        const auto real = std::filesystem::canonical(path, ec);
        if (!ec) target = real.string();
      }
    }
    target_ = target;
    tmp_ = std::make_unique<std::string>(detail::temporary_template(target));
    const int fd = ::mkstemp(tmp_->data());  // O_CREAT | O_EXCL, a fresh name
    if (fd < 0) {
      const int err = errno;
      throw Error(path_, "cannot create temporary file beside it: " + detail::errno_text(err), err);
    }
    lock_ = detail::lock_temporary(fd);
    slot_ = detail::register_temporary(tmp_->c_str());
    (void)::fchmod(fd, mode);
    file_ = ::fdopen(fd, "wb");
    if (!file_) {
      const int err = errno;
      ::close(fd);
      discard();
      throw Error(path_, "cannot open a temporary file: " + detail::errno_text(err), err);
    }
#else
    target_ = path;
    for (int i = 0; i < 1000 && !file_; ++i) {
      tmp_ = std::make_unique<std::string>(path + ".tmp-" + std::to_string(i));
      if (std::FILE* probe = std::fopen(tmp_->c_str(), "rb")) {
        std::fclose(probe);
        continue;
      }
      file_ = std::fopen(tmp_->c_str(), "wb");
    }
    if (!file_) fail("cannot create a temporary file beside it");
    slot_ = detail::register_temporary(tmp_->c_str());
#endif
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() {
    if (file_) std::fclose(file_);
    discard();
  }

  /// The temporary being written (empty when the target is written directly).
  std::string temporary() const { return tmp_ ? *tmp_ : std::string(); }

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
    if (direct_) return;
    detail::PendingFile pending;
    pending.tmp = std::move(tmp_);
    pending.target = target_;
    pending.slot = std::exchange(slot_, -1);
    pending.lock = std::exchange(lock_, -1);
    if (detail::CommitGroupBase* group = detail::current_group())
      group->defer(std::move(pending));
    else
      pending.rename();
  }

 private:
  void discard() noexcept {
    if (tmp_) std::remove(tmp_->c_str());
    detail::unregister_temporary(std::exchange(slot_, -1));
    detail::release_lock(lock_);
    tmp_.reset();
  }
  [[noreturn]] void fail(const std::string& what) { fail_errno(what, errno); }
  [[noreturn]] void fail_errno(const std::string& what, int err) {
    throw Error(path_, what + (err ? ": " + detail::errno_text(err) : std::string()), err);
  }

  std::string path_, target_;
  std::unique_ptr<std::string> tmp_;
  int slot_ = -1;
  int lock_ = -1;
  std::FILE* file_ = nullptr;
  bool direct_ = false;
};

/// Removes the temporaries that writers of `target` killed without a chance to clean up (SIGKILL,
/// a power cut) left beside it: AtomicFile's "<name>.tmp-XXXXXX" files and StagingDir's
/// "<name>.tmp-XXXXXX" folders (mode 0700, this user's, holding StagingDir's marker file) that no
/// running process holds locked and that are older than a second. Returns how many it removed.
/// For programs: knnocc calls it for each output before writing.
inline std::size_t remove_stale_temporaries(const std::string& target) {
  std::size_t removed = 0;
#if KNNOCC_POSIX_FILES
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path real(target);
  if (fs::is_symlink(real, ec)) {  // AtomicFile writes beside the file the link names
    const fs::path resolved = fs::canonical(real, ec);
    if (ec) return 0;  // a dangling link: nothing of ours can lie beside it
    real = resolved;
  }
  const fs::path tmpl(detail::temporary_template(real.string()));
  const std::string prefix =
      tmpl.filename().string().substr(0, tmpl.filename().string().size() - 6);
  const fs::path dir = tmpl.has_parent_path() ? tmpl.parent_path() : fs::path(".");
  const auto now = std::time(nullptr);
  const auto ours = [&](const std::string& name) {  // prefix + six of mkstemp's characters
    if (name.size() != prefix.size() + 6 || name.compare(0, prefix.size(), prefix) != 0)
      return false;
    return std::all_of(name.end() - 6, name.end(),
                       [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; });
  };
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path path = it->path();
    if (!ours(path.filename().string())) continue;
    std::error_code type_ec;
    const fs::file_type type = it->symlink_status(type_ec).type();
    // Only files and folders: opening a FIFO of that name would wait for a writer.
    if (type_ec || (type != fs::file_type::regular && type != fs::file_type::directory)) continue;
    const bool folder = type == fs::file_type::directory;
    // A folder is StagingDir's only while it holds the marker (not the user's own folder).
    if (folder &&
        fs::symlink_status(path / detail::kStagingMarker, type_ec).type() != fs::file_type::regular)
      continue;
    const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    struct stat st;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::fstat(fd, &st) == 0 && st.st_mtime + 1 < now) {
      if (!folder && S_ISREG(st.st_mode) && ::unlink(path.c_str()) == 0) {
        ++removed;
      } else if (folder && S_ISDIR(st.st_mode) && (st.st_mode & 07777) == 0700 &&
                 st.st_uid == ::geteuid()) {
        std::error_code rm;
        if (fs::remove_all(path, rm) > 0 && !rm) ++removed;
      }
    }
    ::close(fd);
  }
#else
  (void)target;
#endif
  return removed;
}

/// Commits the AtomicFiles of one thread as a set: while the group is open, their commit() only
/// closes them; commit() here renames them all, after every one was written completely. Without
/// commit() (an exception while writing any of them) every temporary is removed and no target
/// is touched. (A rename itself failing midway leaves the earlier targets replaced; renames in one
/// directory do not fail once the temporaries exist, short of a concurrent change to it.)
class CommitGroup : public detail::CommitGroupBase {
 public:
  CommitGroup() : outer_(std::exchange(detail::current_group(), this)) {}
  CommitGroup(const CommitGroup&) = delete;
  CommitGroup& operator=(const CommitGroup&) = delete;
  ~CommitGroup() {
    if (detail::current_group() == this) detail::current_group() = outer_;
  }
  void commit() {
    if (detail::current_group() == this) detail::current_group() = outer_;
    for (auto& f : pending_) f.rename();
    pending_.clear();
  }

 private:
  detail::CommitGroupBase* outer_;
};

/// A folder output built aside: files go into a fresh folder "`dir`.tmp-XXXXXX" beside `dir`
/// (path()), and commit() renames it to `dir`. `dir` must not exist or be an empty folder
/// (replaced), or a folder the `replaceable` predicate accepts (moved aside, and removed once the
/// new folder is in place); any other non-empty folder is refused in the constructor, before any
/// work. Without commit() the staging folder and its contents are removed (also on
/// SIGINT/SIGTERM with remove_temporaries_on_signal). The staging folder is locked (flock) while
/// it lives, so that a later StagingDir of the same target removes it if its writer was killed
/// (SIGKILL, a power cut): see remove_stale_temporaries().
class StagingDir {
 public:
  /// Says whether an existing non-empty folder may be replaced as a whole (e.g. the output of an
  /// earlier run of the same command); null: never.
  using Replaceable = bool (*)(const std::string& dir);

  explicit StagingDir(const std::string& dir, Replaceable replaceable = nullptr)
      : dir_(dir), replaceable_(replaceable) {
    namespace fs = std::filesystem;
    if (dir.empty()) throw Error(dir, "empty output folder name");
    check_target(dir, replaceable_);
    fs::path target(dir);
    if (!target.has_filename()) target = target.parent_path();  // "out/" -> "out"
    const fs::path parent = target.parent_path();
    remove_stale_temporaries(target.string());
    tmp_ = std::make_unique<std::string>(detail::temporary_template(target.string()));
#if KNNOCC_POSIX_FILES
    if (!::mkdtemp(tmp_->data())) {
      const int err = errno;
      throw Error(dir, "cannot create a folder beside it: " + detail::errno_text(err), err);
    }
    const int fd = ::open(tmp_->c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0 && ::flock(fd, LOCK_EX | LOCK_NB) == 0)
      lock_ = fd;
    else if (fd >= 0)
      ::close(fd);
    const int marker = ::open(marker_path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (marker >= 0) ::close(marker);
#else
    std::error_code ec;
    tmp_->replace(tmp_->size() - 6, 6, "000000");
    if (!fs::create_directory(*tmp_, ec)) throw Error(dir, "cannot create a folder beside it");
#endif
    slot_ = detail::register_temporary(tmp_->c_str(), true);
  }
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;
  ~StagingDir() {
    if (tmp_) {
      std::error_code ec;
      std::filesystem::remove_all(*tmp_, ec);
      detail::unregister_temporary(slot_);
    }
    detail::release_lock(lock_);
  }

  /// Where to write the folder's contents until commit().
  const std::string& path() const { return *tmp_; }

  void commit() {
    check_target(dir_, replaceable_);
    std::string old;  // a replaceable earlier folder, moved aside until the new one is in place
    if (std::filesystem::is_directory(dir_)) {
      std::error_code ec;
      std::filesystem::remove(dir_, ec);  // empty: removed; otherwise moved aside
      if (std::filesystem::exists(dir_)) {
        old = *tmp_ + ".old";
        if (std::rename(dir_.c_str(), old.c_str()) != 0) {
          const int err = errno;
          throw Error(dir_, "cannot move the earlier folder aside: " + detail::errno_text(err),
                      err);
        }
      }
    }
#if KNNOCC_POSIX_FILES
    // The output holds only what was written into it, with the mode mkdir would give it (mkdtemp
    // made it 0700).
    std::remove(marker_path().c_str());
    (void)::chmod(tmp_->c_str(), detail::new_folder_mode());
#endif
    if (std::rename(tmp_->c_str(), dir_.c_str()) != 0) {
      const int err = errno;
      if (!old.empty()) std::rename(old.c_str(), dir_.c_str());  // the earlier folder back
      throw Error(dir_, "cannot rename '" + *tmp_ + "' to the target: " + detail::errno_text(err),
                  err);
    }
    if (!old.empty()) {
      std::error_code ec;
      std::filesystem::remove_all(old, ec);
    }
    detail::unregister_temporary(std::exchange(slot_, -1));
    detail::release_lock(lock_);
    tmp_.reset();
  }

  /// Throws unless `dir` is absent, an empty folder, or a folder `replaceable` accepts.
  static void check_target(const std::string& dir, Replaceable replaceable = nullptr) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const auto st = fs::symlink_status(dir, ec);
    if (ec || st.type() == fs::file_type::not_found) return;
    if (st.type() != fs::file_type::directory)
      throw Error(dir, "exists and is not a folder; give a new folder name");
    if (!fs::is_empty(dir, ec) && !(replaceable && replaceable(dir)))
      throw Error(dir, "folder is not empty; give a new or empty folder (nothing is overwritten)");
  }

 private:
  std::string dir_;
  Replaceable replaceable_ = nullptr;
  std::unique_ptr<std::string> tmp_;
  int slot_ = -1;
  int lock_ = -1;  // a descriptor of the staging folder holding its flock, or -1

  std::string marker_path() const { return *tmp_ + "/" + detail::kStagingMarker; }
};

}  // namespace knnocc::io

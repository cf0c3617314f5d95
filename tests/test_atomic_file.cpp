// io::AtomicFile, io::CommitGroup, io::StagingDir: unique temporaries, devices and FIFOs written
// in place, sets committed together, temporaries removed on SIGTERM.

#include <doctest/doctest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

#include <knnocc/io/atomic_file.hpp>

#include "test_support.hpp"

#if defined(__unix__) || defined(__APPLE__)
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#define KNNOCC_TEST_POSIX 1
#else
#define KNNOCC_TEST_POSIX 0
#endif

namespace {

namespace fs = std::filesystem;
namespace io = knnocc::io;
using knnocc::test::has_temporary_beside;
using knnocc::test::read_file;
using knnocc::test::write_file;

fs::path fresh_dir(const std::string& name) {
  const fs::path d =
      knnocc::test::scratch_dir("atomic_file") / (name + std::to_string(std::random_device{}()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write_text(const std::string& path, const std::string& text) {
  io::AtomicFile f(path);
  f.write(text);
  f.commit();
}

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

#if KNNOCC_TEST_POSIX
// Runs body(stop) in a child process; stop() tells the parent and waits for a signal to end the
// child. Returns the child's pid once it waits, its files as body left them.
template <class Body>
pid_t stopped_child(Body&& body) {
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::close(ready[0]);
    body([&] {
      const char go = 1;
      if (::write(ready[1], &go, 1) != 1) ::_exit(3);
      ::pause();
      ::_exit(4);
    });
    ::_exit(5);
  }
  ::close(ready[1]);
  char go = 0;
  REQUIRE(::read(ready[0], &go, 1) == 1);
  ::close(ready[0]);
  return child;
}
#endif

}  // namespace

TEST_CASE("io.atomic_file: commit replaces the target, no commit leaves it as it was") {
  const fs::path d = fresh_dir("commit");
  const std::string p = (d / "out.txt").string();
  write_text(p, "first\n");
  CHECK(read_file(p) == "first\n");
  {
    io::AtomicFile f(p);
    f.write("second, never committed\n");
    CHECK(fs::exists(f.temporary()));
    CHECK(fs::path(f.temporary()).parent_path() == d);
  }
  CHECK(read_file(p) == "first\n");
  CHECK_FALSE(has_temporary_beside(p));
  CHECK(entries(d) == 1);
}

TEST_CASE("io.atomic_file: a user's <target>.tmp is neither used nor removed") {
  const fs::path d = fresh_dir("user_tmp");
  const std::string p = (d / "victim.txt").string();
  write_file(p + ".tmp", "mine");
  write_text(p, "output");
  CHECK(read_file(p + ".tmp") == "mine");
  CHECK(read_file(p) == "output");
}

TEST_CASE("io.atomic_file: writers of one path never share a temporary") {
  const fs::path d = fresh_dir("concurrent");
  const std::string p = (d / "same.txt").string();
  io::AtomicFile a(p), b(p);
  CHECK(a.temporary() != b.temporary());
  const std::string long_a(100000, 'a'), long_b(50000, 'b');
  a.write(long_a);
  b.write(long_b);
  a.commit();
  CHECK(read_file(p) == long_a);
  b.commit();
  CHECK(read_file(p) == long_b);  // the last commit wins, whole
  CHECK(entries(d) == 1);
}

TEST_CASE("io.atomic_file: a folder as target is an error naming it") {
  const fs::path d = fresh_dir("folder");
  try {
    io::AtomicFile f(d.string());
    FAIL("no error");
  } catch (const io::Error& e) {
    CHECK(e.file() == d.string());
    CHECK(e.problem() == "is a directory");
  }
  CHECK_THROWS_AS(io::AtomicFile(""), io::Error);
  CHECK_THROWS_AS(io::AtomicFile((d / "missing" / "x.txt").string()), io::Error);
}

#if KNNOCC_TEST_POSIX
TEST_CASE("io.atomic_file: permissions: 0666 minus the umask when new, kept when replaced") {
  const fs::path d = fresh_dir("mode");
  const std::string p = (d / "m.txt").string();
  const mode_t mask = ::umask(022);
  ::umask(mask);
  write_text(p, "x");
  struct stat st;
  REQUIRE(::stat(p.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == (0666 & ~mask));
  REQUIRE(::chmod(p.c_str(), 0640) == 0);
  write_text(p, "y");
  REQUIRE(::stat(p.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0640);
}

TEST_CASE("io.atomic_file: a device or FIFO is written in place, never replaced") {
  if (::access("/dev/null", W_OK) == 0) {
    write_text("/dev/null", "discarded\n");
    struct stat st;
    REQUIRE(::stat("/dev/null", &st) == 0);
    CHECK(S_ISCHR(st.st_mode));
  }
  const fs::path d = fresh_dir("fifo");
  const std::string fifo = (d / "pipe").string();
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  std::string received;
  std::thread reader([&] { received = read_file(fifo); });
  write_text(fifo, "through the pipe\n");
  reader.join();
  CHECK(received == "through the pipe\n");
  CHECK(fs::is_fifo(fifo));
  CHECK(entries(d) == 1);
}

TEST_CASE("io.atomic_file: a symbolic link is followed; the link stays") {
  const fs::path d = fresh_dir("symlink");
  const std::string real = (d / "real.txt").string(), link = (d / "link.txt").string();
  write_text(real, "old");
  fs::create_symlink("real.txt", link);
  write_text(link, "new");
  CHECK(fs::is_symlink(link));
  CHECK(read_file(real) == "new");
}
#endif

TEST_CASE("io.commit_group: all targets replaced together, or none") {
  const fs::path d = fresh_dir("group");
  const std::string a = (d / "a.txt").string(), b = (d / "b.txt").string();
  write_text(a, "old a");
  try {
    io::CommitGroup group;
    write_text(a, "new a");  // closed, not yet renamed
    CHECK(read_file(a) == "old a");
    throw std::runtime_error("second output failed");
  } catch (const std::runtime_error&) {
  }
  CHECK(read_file(a) == "old a");
  CHECK_FALSE(fs::exists(b));
  CHECK(entries(d) == 1);  // the closed temporary is gone too
  {
    io::CommitGroup group;
    write_text(a, "new a");
    write_text(b, "new b");
    CHECK(read_file(a) == "old a");
    group.commit();
  }
  CHECK(read_file(a) == "new a");
  CHECK(read_file(b) == "new b");
  CHECK(entries(d) == 2);
  write_text(a, "after the group");  // no group open: renamed at once
  CHECK(read_file(a) == "after the group");
}

TEST_CASE("io.staging_dir: built aside, renamed when complete; a non-empty folder is refused") {
  const fs::path d = fresh_dir("staging");
  const std::string out = (d / "seq").string();
  {
    io::StagingDir stage(out);
    fs::create_directories(fs::path(stage.path()) / "clouds");
    write_text((fs::path(stage.path()) / "clouds" / "0.txt").string(), "cloud");
    CHECK_FALSE(fs::exists(out));
  }  // not committed: removed with its contents
  CHECK(entries(d) == 0);
  {
    io::StagingDir stage(out);
    write_text((fs::path(stage.path()) / "poses.txt").string(), "poses");
    stage.commit();
  }
  CHECK(read_file(fs::path(out) / "poses.txt") == "poses");
  CHECK(entries(d) == 1);
  CHECK_THROWS_WITH_AS(io::StagingDir{out}, doctest::Contains("folder is not empty"), io::Error);
  const std::string empty = (d / "empty").string();
  fs::create_directory(empty);
  {
    io::StagingDir stage(empty);  // an empty folder is replaced
    write_text((fs::path(stage.path()) / "x").string(), "x");
    stage.commit();
  }
  CHECK(read_file(fs::path(empty) / "x") == "x");
  write_text((d / "file").string(), "f");
  CHECK_THROWS_WITH_AS(io::StagingDir{(d / "file").string()}, doctest::Contains("is not a folder"),
                       io::Error);
}

#if KNNOCC_TEST_POSIX
TEST_CASE("io.atomic_file: SIGTERM removes the temporaries, then ends the process by the signal") {
  const fs::path d = fresh_dir("signal");
  const std::string file = (d / "out.txt").string(), folder = (d / "seq").string();
  const pid_t child = stopped_child([&](auto stop) {
    io::remove_temporaries_on_signal();
    io::AtomicFile f(file);
    f.write("partial");
    io::StagingDir stage(folder);
    fs::create_directories(fs::path(stage.path()) / "clouds");
    io::AtomicFile inner((fs::path(stage.path()) / "clouds" / "0.ply").string());
    inner.write("partial");
    write_text((fs::path(stage.path()) / "poses.txt").string(), "done");
    stop();  // SIGTERM arrives here
  });
  CHECK(entries(d) == 2);  // out.txt's temporary and the staging folder
  ::kill(child, SIGTERM);
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);
  CHECK(entries(d) == 0);
}

TEST_CASE(
    "io.atomic_file: a killed writer's temporary is removed on the next start, a live one's kept") {
  const fs::path d = fresh_dir("stale");
  const std::string target = (d / "map.ot").string();
  // A child writes target (alone, or in a CommitGroup waiting for its rename) and stops.
  auto writer = [&](bool pending) {
    return stopped_child([&](auto stop) {
      io::CommitGroup group;
      io::AtomicFile f(target);
      f.write("partial");
      if (pending) f.commit();  // closed, renamed by group.commit() (never reached)
      stop();
    });
  };
  auto age = [&]() {  // every temporary a minute old: only the locks tell them apart
    for (const auto& e : fs::directory_iterator(d))
      fs::last_write_time(e.path(), fs::file_time_type::clock::now() - std::chrono::minutes(1));
  };
  auto kill = [](pid_t child) {
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
  };
  const pid_t killed = writer(false);
  kill(killed);  // SIGKILL: no handler runs, the temporary stays
  const pid_t writing = writer(false), waiting = writer(true);
  write_file(d / "map.ot.tmp", "a user's file");
  write_file(d / "map.ot.tmp-1234567", "not a temporary's name");
  age();
  CHECK(entries(d) == 5);
  CHECK(io::remove_stale_temporaries(target) == 1);  // the killed writer's
  CHECK(entries(d) == 4);
  write_file(d / "map.ot.tmp-abcdef", "fresh, unlocked");  // too young to judge
  CHECK(io::remove_stale_temporaries(target) == 0);
  kill(writing);
  kill(waiting);
  age();
  CHECK(io::remove_stale_temporaries(target) == 3);
  CHECK(entries(d) == 2);
  CHECK(fs::exists(d / "map.ot.tmp"));
  CHECK(fs::exists(d / "map.ot.tmp-1234567"));
}
#endif

// detail::ThreadPool: every worker runs each job once; a thread that cannot start is an error
// (std::system_error naming it), never a hang.

#include <doctest/doctest.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include <knnocc/insertion/detail/thread_pool.hpp>

#include "test_support.hpp"

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <csignal>
#endif

namespace {

using knnocc::detail::ThreadPool;

std::atomic<unsigned> started{0};

// Starts workers 1 and 2; worker 3 fails as pthread_create does at a process or memory limit.
std::thread start_two(unsigned w, std::function<void()> body) {
  if (w >= 3) throw std::system_error(EAGAIN, std::generic_category(), "pthread_create");
  ++started;
  return std::thread(std::move(body));
}

}  // namespace

TEST_CASE("thread_pool: each job runs once on every worker") {
  ThreadPool pool(5);
  std::vector<std::atomic<int>> calls(5);
  auto job = [&](unsigned w) { ++calls[w]; };
  for (int r = 0; r < 10; ++r) pool.run(job);
  for (auto& c : calls) CHECK(c.load() == 10);
}

TEST_CASE("thread_pool: a thread that cannot start is an error naming it, the others joined") {
  started = 0;
  try {
    ThreadPool pool(8, start_two);
    FAIL("no error");
  } catch (const std::system_error& e) {
    CHECK(e.code() == std::errc::resource_unavailable_try_again);
    CHECK(std::string(e.what()).find("cannot start thread 3 of 8") != std::string::npos);
  }
  CHECK(started == 2);  // both were started and are joined (otherwise std::terminate)
}

#if defined(__linux__)
TEST_CASE("thread_pool: at a real address-space limit the constructor throws, never hangs") {
  // In a child: an address space too small for 64 thread stacks. The child reports how the
  // constructor ended: 0 = std::system_error, 1 = no error, 2 = another exception.
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    long pages = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%ld", &pages) != 1) pages = 0;
      std::fclose(f);
    }
    const rlim_t limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE)) +
                         (rlim_t{64} << 20);  // room for a few 8 MB stacks, not 64
    const rlimit rl{limit, limit};
    if (pages == 0 || ::setrlimit(RLIMIT_AS, &rl) != 0) ::_exit(3);
    try {
      ThreadPool pool(64);
      ::_exit(1);
    } catch (const std::system_error&) {
      ::_exit(0);
    } catch (...) {
      ::_exit(2);
    }
  }
  int status = 0;
  pid_t done = 0;
  for (int i = 0; i < 600 && done == 0; ++i) {  // 60 s at most, then it is a hang
    done = ::waitpid(child, &status, WNOHANG);
    if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (done == 0) {
    ::kill(child, SIGKILL);
    ::waitpid(child, &status, 0);
    FAIL("ThreadPool(64) hung at the address-space limit");
  }
  REQUIRE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 3) {
    knnocc::test::skip("cannot set RLIMIT_AS here");
    return;
  }
  if (WEXITSTATUS(status) == 1) {
    knnocc::test::skip("64 threads fit in the limit here (small default stacks)");
    return;
  }
  CHECK(WEXITSTATUS(status) == 0);
}
#endif

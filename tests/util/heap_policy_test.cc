/// @file heap_policy_test.cc
/// @brief P2I_HEAP: its values, the error for a bad one, and that `retain` really keeps freed
/// memory (a large block allocated again costs no page faults), each measured in a child process
/// because the policy is the whole process's.
#include "util/heap_policy.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>

namespace p2i::util {
namespace {

constexpr std::size_t kBlock = 64u << 20;  // above glibc's largest dynamic mmap threshold (32 MB)

/// Makes the compiler assume `p`'s memory is read, so writes to it and its malloc stay.
void Escape(void* p) { asm volatile("" : : "g"(p) : "memory"); }

long MinorFaults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

/// In a child process: applies `policy`, allocates, touches and frees a 64 MB block, then
/// allocates and touches one again, and returns the page faults of that second block (-1 when
/// the child failed).
long FaultsOfASecondBlock(HeapPolicy policy) {
  int fds[2];
  REQUIRE(pipe(fds) == 0);
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    close(fds[0]);
    long faults = -1;
    if (ApplyHeapPolicy(policy)) {
      auto* first = static_cast<char*>(std::malloc(kBlock));
      if (first != nullptr) {
        std::memset(first, 1, kBlock);
        Escape(first);
        std::free(first);
        const long before = MinorFaults();
        auto* second = static_cast<char*>(std::malloc(kBlock));
        if (second != nullptr) {
          std::memset(second, 2, kBlock);
          Escape(second);
          faults = MinorFaults() - before;
          std::free(second);
        }
      }
    }
    const ssize_t n = write(fds[1], &faults, sizeof faults);
    _exit(n == sizeof faults ? 0 : 1);
  }
  close(fds[1]);
  long faults = -1;
  const ssize_t n = read(fds[0], &faults, sizeof faults);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  REQUIRE(n == static_cast<ssize_t>(sizeof faults));
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  return faults;
}

TEST_CASE("P2I_HEAP: unset or empty is retain, the two names parse, anything else is an error "
          "naming the variable and the choices",
          "[unit]") {
  CHECK(ParseHeapPolicy(nullptr) == HeapPolicy::kRetain);
  CHECK(ParseHeapPolicy("") == HeapPolicy::kRetain);
  CHECK(ParseHeapPolicy("retain") == HeapPolicy::kRetain);
  CHECK(ParseHeapPolicy("system") == HeapPolicy::kSystem);
  try {
    ParseHeapPolicy("fast");
    FAIL("a bad value was accepted");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("P2I_HEAP='fast'") != std::string::npos);
    CHECK(what.find("P2I_HEAP=retain") != std::string::npos);
    CHECK(what.find("P2I_HEAP=system") != std::string::npos);
  }
  CHECK(ApplyHeapPolicy(HeapPolicy::kSystem));
}

TEST_CASE("Heap policy retain: a large block freed and allocated again costs no page faults, "
          "and with the C library's defaults it does",
          "[unit]") {
#if !defined(__GLIBC__)
  SKIP("the heap policy acts on glibc's allocator only");
#endif
  const long pages = static_cast<long>(kBlock / static_cast<std::size_t>(sysconf(_SC_PAGESIZE)));
  const long retained = FaultsOfASecondBlock(HeapPolicy::kRetain);
  const long system = FaultsOfASecondBlock(HeapPolicy::kSystem);
  INFO("pages " << pages << ", faults with retain " << retained << ", with system " << system);
  REQUIRE(retained >= 0);
  REQUIRE(system >= 0);
  CHECK(retained < pages / 100);
  // glibc maps a 64 MB block of its own and unmaps it when freed, so the second block is new
  // memory: one fault per page, unless the kernel backs it with huge pages (THP "always"),
  // where the comparison below cannot tell the two policies apart.
  if (system < pages / 10) {
    WARN("the kernel backs large blocks with huge pages: the faults saved are not visible here");
  } else {
    CHECK(system > 50 * (retained + 1));
  }
}

}  // namespace
}  // namespace p2i::util

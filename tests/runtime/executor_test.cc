/// @file executor_test.cc
/// @brief The single-threaded executor: timers, posted tasks, stop.
#include <catch2/catch.hpp>

#include <thread>

#include "nodes/runtime/executor.h"
#include "nodes/runtime/shutdown.h"

using p2i::runtime::Executor;

TEST_CASE("Executor runs timers and posted tasks on the spinning thread and stops", "[unit]") {
  p2i::runtime::Shutdown::ResetForTesting();
  Executor ex;
  int ticks = 0;
  std::thread::id timer_thread, task_thread;
  ex.AddTimer(std::chrono::milliseconds(10), [&] {
    ++ticks;
    timer_thread = std::this_thread::get_id();
    if (ticks == 5) ex.Stop();
  });
  std::thread poster([&] { ex.Post([&] { task_thread = std::this_thread::get_id(); }); });
  ex.Spin();
  poster.join();
  CHECK(ticks == 5);
  CHECK(timer_thread == std::this_thread::get_id());
  CHECK(task_thread == std::this_thread::get_id());
  CHECK_FALSE(ex.SpinOnce());
}

TEST_CASE("Executor stops when a shutdown is requested", "[unit]") {
  p2i::runtime::Shutdown::ResetForTesting();
  Executor ex;
  std::thread stopper([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    p2i::runtime::Shutdown::Request();
  });
  ex.Spin();  // would never return without the request
  stopper.join();
  CHECK(p2i::runtime::Shutdown::Requested());
  p2i::runtime::Shutdown::ResetForTesting();
  CHECK_FALSE(p2i::runtime::Shutdown::Requested());
}

TEST_CASE("Executor: a cancelled timer no longer runs", "[unit]") {
  p2i::runtime::Shutdown::ResetForTesting();
  Executor ex;
  int a = 0, b = 0;
  int id_b = ex.AddTimer(std::chrono::milliseconds(5), [&] { ++b; });
  ex.AddTimer(std::chrono::milliseconds(5), [&] { if (++a == 1) ex.CancelTimer(id_b); if (a == 10) ex.Stop(); });
  ex.Spin();
  CHECK(a == 10);
  CHECK(b <= 1);
}

TEST_CASE("Shutdown::WaitFor returns at once for a deadline already past", "[unit]") {
  // A negative timeout used to reach poll() as is, which then waited forever (p2i play hung
  // when it was descheduled past a message's due time).
  p2i::runtime::Shutdown::ResetForTesting();
  CHECK_FALSE(p2i::runtime::Shutdown::WaitFor(std::chrono::milliseconds(-5)));
  CHECK_FALSE(p2i::runtime::Shutdown::WaitFor(std::chrono::nanoseconds(-1)));
  CHECK_FALSE(p2i::runtime::Shutdown::WaitFor(std::chrono::milliseconds(1)));
}

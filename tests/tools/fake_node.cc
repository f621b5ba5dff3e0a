/// @file fake_node.cc
/// @brief p2i_fake_node: a stand-in node for launcher tests. Takes the node command line of
/// the CLI contract and, as extra arguments, what to do:
///   --lines N          print "line 0" .. "line N-1"
///   --print-env NAME   print NAME=<value>
///   --start-file F     append one line to F per start (counts respawns)
///   --pid-dir D        create D/<pid> (tests find the children through it)
///   --sleep S          stay alive S seconds (default 0), --forever: until a signal
///   --exit-code N      exit code when done (default 0)
///   --crash            die by SIGSEGV when done
///   --ignore-sigterm   ignore SIGTERM (to test the SIGKILL escalation)
/// It prints its argv and the content of every --params-file, flushing each line.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

volatile sig_atomic_t g_term = 0;
void OnTerm(int) { g_term = 1; }

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  // Handlers first: tests signal the node as soon as its --pid-dir file appears.
  bool ignore_term = false;
  for (const auto& a : args) ignore_term = ignore_term || a == "--ignore-sigterm";
  ::signal(SIGTERM, ignore_term ? SIG_IGN : OnTerm);
  ::signal(SIGINT, OnTerm);
  std::string line = "argv:";
  for (const auto& a : args) line += " " + a;
  std::printf("%s\n", line.c_str());
  double sleep_s = 0;
  bool forever = false, crash = false;
  int exit_code = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool has_value = i + 1 < args.size();
    if (a == "--params-file" && has_value) {
      std::ifstream in(args[i + 1]);
      std::string l;
      while (std::getline(in, l)) std::printf("param %s\n", l.c_str());
    } else if (a == "--lines" && has_value) {
      for (int k = 0; k < std::atoi(args[i + 1].c_str()); ++k) std::printf("line %d\n", k);
    } else if (a == "--print-env" && has_value) {
      const char* v = std::getenv(args[i + 1].c_str());
      std::printf("%s=%s\n", args[i + 1].c_str(), v ? v : "(unset)");
    } else if (a == "--start-file" && has_value) {
      std::ofstream(args[i + 1], std::ios::app) << ::getpid() << "\n";
    } else if (a == "--pid-dir" && has_value) {
      std::ofstream(args[i + 1] + "/" + std::to_string(::getpid())) << "\n";
    } else if (a == "--sleep" && has_value) {
      sleep_s = std::atof(args[i + 1].c_str());
    } else if (a == "--exit-code" && has_value) {
      exit_code = std::atoi(args[i + 1].c_str());
    } else if (a == "--forever") {
      forever = true;
    } else if (a == "--crash") {
      crash = true;
    }
  }
  std::fflush(stdout);
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                         std::chrono::duration<double>(sleep_s));
  while (!g_term && (forever || std::chrono::steady_clock::now() < until)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (g_term) {
    std::printf("got SIGTERM\n");
    std::fflush(stdout);
    return 0;
  }
  std::fprintf(stderr, "done\n");
  if (crash) {
    ::signal(SIGSEGV, SIG_DFL);
    ::raise(SIGSEGV);
  }
  return exit_code;
}

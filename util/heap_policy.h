/// @file heap_policy.h
/// @brief What a p2i process does with the memory it frees (docs/RUNTIME.md "Heap"): by default
/// it keeps it for its next allocations instead of handing it back to the kernel.
///
/// glibc serves large blocks (from 128 KB up, rising to 32 MB as such blocks are freed) with
/// their own mmap and returns them to the kernel when they are freed, and trims the top of the
/// heap above 128 KB. Every such block allocated again costs a page fault per 4 KB page on its
/// first touch: ~10-25 us each on the virtual machines p2i was measured on. The fusion method
/// allocates such blocks on every frame and view (Open3D's tensors, the TSDF's hash map as it
/// grows, view buffers): `fusion_bench` took 2.6x the page faults and ~25 % more time without
/// this policy (docs/RESULTS.md, session 49). `retain` sets glibc's M_MMAP_MAX to 0 (every block
/// comes from the heap, where a freed block is reused) and M_TRIM_THRESHOLD to its maximum (the
/// heap is never trimmed), the settings real-time robotics processes use to avoid page faults.
/// The cost: a process keeps its peak heap until it exits (fusion_bench: +6-10 % peak RSS).
/// `P2I_HEAP=system` keeps glibc's defaults. Blocks larger than a thread's arena (64 MB) still
/// come from mmap when a thread other than the main one allocates them.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace p2i::util {

enum class HeapPolicy {
  kRetain,  ///< freed memory stays in the process (the default)
  kSystem,  ///< the C library's defaults
};

/// The policy named by the value of P2I_HEAP: unset or empty -> kRetain; "retain"; "system".
/// Anything else throws std::invalid_argument naming the variable, the value and the choices.
inline HeapPolicy ParseHeapPolicy(const char* value) {
  if (value == nullptr || *value == '\0') return HeapPolicy::kRetain;
  const std::string v(value);
  if (v == "retain") return HeapPolicy::kRetain;
  if (v == "system") return HeapPolicy::kSystem;
  throw std::invalid_argument(
      "environment variable P2I_HEAP='" + v +
      "' is not a heap policy: set P2I_HEAP=retain (the default: freed memory is kept for reuse) "
      "or P2I_HEAP=system (the C library's defaults), or unset it");
}

/// Applies `policy` to this process's heap. Returns true when the policy is in effect: always for
/// kSystem (nothing to change), for kRetain where the C library is glibc and accepted both
/// settings. Call it first thing in main(), before threads start allocating.
inline bool ApplyHeapPolicy(HeapPolicy policy) {
  if (policy == HeapPolicy::kSystem) return true;
#if defined(__GLIBC__)
  const bool no_mmap = mallopt(M_MMAP_MAX, 0) == 1;
  const bool no_trim = mallopt(M_TRIM_THRESHOLD, -1) == 1;  // -1: the largest size_t
  return no_mmap && no_trim;
#else
  return false;
#endif
}

/// ParseHeapPolicy(getenv("P2I_HEAP")), applied. Throws std::invalid_argument for a bad value.
inline bool ApplyHeapPolicyFromEnvironment() {
  return ApplyHeapPolicy(ParseHeapPolicy(std::getenv("P2I_HEAP")));
}

/// For a program's main(): ApplyHeapPolicyFromEnvironment(), or, for a bad P2I_HEAP, prints
/// "PROGRAM: configuration error: ..." to stderr and returns false (exit 2, docs/RUNTIME.md).
inline bool ApplyHeapPolicyOrReport(const std::string& program) {
  try {
    ApplyHeapPolicyFromEnvironment();
    return true;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: configuration error: %s\n", program.c_str(), e.what());
    return false;
  }
}

}  // namespace p2i::util

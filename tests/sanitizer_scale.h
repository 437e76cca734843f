#pragma once
// How much of a heavy property test to run in this build. Under AddressSanitizer + UBSan (scripts/strata.sh
// sanitize) the engine runs 5 to 10 times slower and the five heaviest tests took 4.6 of the sanitizer suite's
// 10 CPU-minutes. There they run a fraction of their trials: the sanitizers check every code path the full run
// takes, on fewer inputs, while the Release suite keeps the full counts behind the statistical claims. Rejected:
// leaving those tests out of the sanitizer run (a label), which would drop their code paths from it entirely.
namespace strata::test {

#if defined(STRATA_ASAN)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif

// `full` in a plain build, full / divisor (at least 1) under the sanitizers.
constexpr int trials_for_build(int full, int divisor) {
  return kSanitizedBuild ? (full / divisor > 0 ? full / divisor : 1) : full;
}

}  // namespace strata::test

#pragma once
// The job convention every per-frame system follows (ozz-animation's runtime jobs; notes/style-anchors.md):
//
//   struct SomeJob {
//     <shared immutable rig data>  by const pointer, null until set
//     ColumnView<const T> ...;     inputs: what the system reads
//     ColumnView<T> ...;           outputs: what it writes (and nothing else)
//     bool validate() const;       every precondition, no side effects
//     bool run() const;            validate() first; false and nothing written when invalid
//   };
//
// A job owns nothing and allocates nothing in run(): output buffers that depend on the crowd size are grown by
// the caller (or by the make_*_job helper, outside run()), scratch lives on the stack or in per-thread buffers
// that only grow. Nothing in run() throws after validate() passed, so no output is ever half written. Each
// system's header lists what it reads and writes in a comment block at the top; the member types say the same.
//
// Why a struct rather than the free function over a WalkerLanes of 16 mutable pointers it replaces: a function
// that can write every column hides its effects; a job's const views make the reads and writes part of its
// type, so the frame script's data flow (and what may run in parallel) is visible without reading kernels.
#include <stdexcept>
#include <string>

namespace strata {

// The most joints a rig may have for the jobs that keep a walker's per-joint scratch on the stack (skinning's
// 512 3x4 matrices are 24 KiB; IK's double frames 48 KiB), so run() never allocates. Validate() refuses more.
inline constexpr std::size_t kMaxJointsPerRig = 512;

// For the frame script and tools, where invalid inputs are a programming error rather than data to report:
// runs `job` and throws std::logic_error naming the system when it refused. Tests call validate()/run() instead.
template <class Job>
void run_or_throw(const Job& job, const char* system) {
  if (!job.run()) throw std::logic_error(std::string(system) + ": invalid job inputs (validate() failed)");
}

}  // namespace strata

#pragma once
// Host memory as every stage sees it (issue 23): what this process may still take, and the error a
// request that does not fit ends in. Frames (render/frame_memory.h) and scenes (scene/load.h)
// check their estimates against the same figure, before they allocate.
#include <cstdint>
#include <string>

#include "util/error.h"

namespace raysort {

// Host memory this process may still take: MemAvailable, lowered by a cgroup limit when one is set
// (a Slurm job's). RAYSORT_TEST_HOST_MEMORY_BYTES overrides it (tests).
std::uint64_t available_host_memory();

// Thrown when a request does not fit this machine; raysort exits 2 for it (1 for other errors).
class ResourceError : public Error {
 public:
  using Error::Error;
};

// "1.5 GiB"
std::string format_bytes(std::uint64_t bytes);

// a × b and a + b saturating at 2^64 − 1, so that a size a user can type never wraps into a small
// estimate.
std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b);
std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b);

}  // namespace raysort

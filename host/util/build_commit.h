// The commit the running binary was built from (cmake/build_commit.cmake, at every build).
#pragma once

namespace raysort {

// git rev-parse --short=12 HEAD of the source tree at build time, "-dirty" appended when tracked
// files differed from it, "unknown" where git was not available.
const char* build_commit();

}  // namespace raysort

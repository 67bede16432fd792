#pragma once
// The one exception type raysort throws for user-facing failures. Its message is meant to be
// printed as is: it names what failed, on which input, and what to do about it.
#include <stdexcept>
#include <string>

namespace raysort {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace raysort

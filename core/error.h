// The one error type walkvis throws for anything a user can get wrong: a bad or missing input
// file, an option out of range, a budget exceeded. Its message is one line that names what is
// wrong (the file, the option); the command line prints it and exits with status 2. Anything
// else that escapes is a bug.
#pragma once

#include <stdexcept>

namespace walkvis {

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace walkvis

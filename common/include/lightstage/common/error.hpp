#pragma once
// The host's error policy: every failure that a user can cause (bad file, bad
// field, bad value) is an exception whose message names the file, field or
// value and what is wrong; main() catches it once, prints it on one line and
// exits non-zero. Bugs are asserts, not exceptions.

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace lightstage {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bad input from outside: a file, a flag, a field.
class InputError : public Error {
 public:
  using Error::Error;
};

// Formats and throws an InputError.
template <typename... Args>
[[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) {
  throw InputError(fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace lightstage

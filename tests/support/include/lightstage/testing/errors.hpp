#pragma once
// The message of the InputError that `action` throws, or "(no InputError)",
// so tests can assert on what a user would read.

#include "lightstage/common/error.hpp"

#include <functional>
#include <string>

namespace lightstage::testing {

inline std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

}  // namespace lightstage::testing

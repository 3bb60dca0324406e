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

// The message of an Error that is not the input's fault (a device or a full
// disk), or "(InputError) ..." / "(no error)" so that tests can tell them apart.
inline std::string device_error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& e) {
    return std::string("(InputError) ") + e.what();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace lightstage::testing

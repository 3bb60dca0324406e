#pragma once
// The current time as an ISO-8601 UTC string, for manifests and summaries.

#include <string>

namespace lightstage::util {

// e.g. "2024-05-01T12:34:56Z".
std::string utc_timestamp();

}  // namespace lightstage::util

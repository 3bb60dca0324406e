#pragma once
// A rig's identity by content: a hash of the parsed rig in one canonical text
// (every field that describes the dome, LEDs sorted by id and chains by name,
// numbers to full precision), so comments, key order, spacing and the
// description do not change it, and any change to geometry, wiring, limits or
// timing does. The controller reports it in Info; the host compares it with
// its own --rig, because two rigs may share a name.

#include "lightstage/common/rig.hpp"

#include <string>
#include <string_view>

namespace lightstage {

// The canonical text the fingerprint hashes (one "key value" per line).
std::string canonical_rig_text(const Rig& rig);

// 16 hex digits (64-bit FNV-1a of canonical_rig_text): not a defence against
// forgery, a guard against a host and a controller holding different files.
std::string rig_fingerprint(const Rig& rig);

// 16 hex digits (64-bit FNV-1a) of any bytes: whether a file is still the one
// a program wrote, not a defence against forgery.
std::string content_hash(std::string_view bytes);

}  // namespace lightstage

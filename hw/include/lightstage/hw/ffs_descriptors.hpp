#pragma once
// The blobs a FunctionFS function writes to its ep0 before the gadget can be
// bound (layout: linux/usb/functionfs.h, "v2" descriptors): one vendor
// interface (usb_interface.hpp) with a bulk IN and a bulk OUT endpoint, for
// full and high speed, and its name as an en-US string.

#include <cstdint>
#include <vector>

namespace lightstage::hw {

// FUNCTIONFS_DESCRIPTORS_MAGIC_V2 header, flags HAS_FS_DESC | HAS_HS_DESC,
// the two counts, then interface + IN + OUT endpoint descriptors per speed.
std::vector<std::uint8_t> ffs_descriptors();

// FUNCTIONFS_STRINGS_MAGIC header, one language (0x0409), one string: the
// interface name (iInterface = 1).
std::vector<std::uint8_t> ffs_strings();

}  // namespace lightstage::hw

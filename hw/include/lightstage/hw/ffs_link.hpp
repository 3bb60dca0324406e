#pragma once
// ffs:MOUNT — the controller's side of a usb: link: a USB FunctionFS function
// (Linux USB gadget, configfs function "ffs.<name>" mounted at MOUNT, e.g.
// /dev/usb-ffs/lightstage; hw/gadget/lightstage-gadget.sh sets it up).
//
// listen_ffs_link() writes the descriptors and strings (ffs_descriptors.hpp)
// to MOUNT/ep0; only then can the gadget be bound to the UDC. accept() handles
// the ep0 events (BIND, ENABLE, DISABLE, UNBIND, SETUP, ...) and hands out a
// link once the host has configured the device (ENABLE), again after that link
// is destroyed. A DISABLE or UNBIND (cable pulled, host reset, gadget unbound)
// makes the link's reads and writes throw LinkClosed.
//
// A host program that merely exits leaves the function enabled: the controller
// sees no close, and the next host simply starts a new session (Hello) on the
// same link. A write that the host does not take within 5 s throws LinkClosed.

#include "lightstage/common/link.hpp"

#include <memory>
#include <string>

namespace lightstage::hw {

inline constexpr const char* kFfsScheme = "ffs";

// Throws InputError for a malformed URI or a MOUNT that is not a FunctionFS
// mount, LinkClosed when ep0 cannot be opened or refuses the descriptors.
std::unique_ptr<LinkListener> listen_ffs_link(const std::string& uri);

}  // namespace lightstage::hw

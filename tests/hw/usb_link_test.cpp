// usb: links. No USB bus here (and no controller anywhere in CI): test the URI
// rules, that libusb starts and takes a hotplug registration without devices,
// and that a missing controller is reported by VID:PID rather than hanging.
#include "lightstage/hw/usb_link.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/hw/backends.hpp"

#include <gtest/gtest.h>

#include <string>

namespace lightstage::hw {
namespace {

using namespace std::chrono_literals;

std::string parse_error(const std::string& uri) {
  try {
    parse_usb_uri(uri);
  } catch (const InputError& error) {
    return error.what();
  }
  return "accepted";
}

TEST(UsbUri, ParsesVendorProductAndSerial) {
  const UsbDeviceId any = parse_usb_uri("usb:1209:0001");
  EXPECT_EQ(any.vendor_id, 0x1209);
  EXPECT_EQ(any.product_id, 0x0001);
  EXPECT_FALSE(any.serial.has_value());
  const UsbDeviceId one = parse_usb_uri("usb:1D6B:104:dome-7:rev2");
  EXPECT_EQ(one.vendor_id, 0x1d6b);
  EXPECT_EQ(one.product_id, 0x0104);
  EXPECT_EQ(one.serial, "dome-7:rev2");  // everything after the PID, colons included
}

TEST(UsbUri, PrintsBackCanonically) {
  EXPECT_EQ(parse_usb_uri("usb:1D6B:104").uri(), "usb:1d6b:0104");
  EXPECT_EQ(parse_usb_uri("usb:1209:0001:ABC").uri(), "usb:1209:0001:ABC");
}

TEST(UsbUri, ErrorsNameTheUriAndThePart) {
  EXPECT_NE(parse_error("usb:").find("no product ID"), std::string::npos);
  EXPECT_NE(parse_error("usb:1209").find("no product ID"), std::string::npos);
  EXPECT_NE(parse_error("usb::0001").find("vendor ID ''"), std::string::npos);
  EXPECT_NE(parse_error("usb:12345:0001").find("vendor ID '12345'"), std::string::npos);
  EXPECT_NE(parse_error("usb:0x12:0001").find("vendor ID '0x12'"), std::string::npos);
  EXPECT_NE(parse_error("usb:1209:zz").find("product ID 'zz'"), std::string::npos);
  EXPECT_NE(parse_error("usb:1209:-1").find("product ID '-1'"), std::string::npos);
  EXPECT_NE(parse_error("usb:1209:0001:").find("empty serial"), std::string::npos);
  EXPECT_NE(parse_error("serial:/dev/ttyACM0").find("not a usb: URI"), std::string::npos);
  EXPECT_NE(parse_error("usb:1209:zz").find("'usb:1209:zz'"), std::string::npos);
}

#ifdef LIGHTSTAGE_HAVE_LIBUSB

TEST(UsbLink, LibusbStartsAndTakesAHotplugRegistrationWithoutDevices) {
  UsbContext context;
  ASSERT_NE(context.get(), nullptr);
  UsbHotplugWatch watch(context, 0x1209, 0x0001);
  EXPECT_EQ(watch.registered(), UsbContext::has_hotplug());
  const auto events = watch.poll(20ms);
  EXPECT_EQ(events.arrived, 0);
  EXPECT_EQ(events.left, 0);
  // Two watches on one context, and a second context, coexist.
  UsbHotplugWatch second(context, 0x1d6b, 0x0104);
  UsbContext other;
  UsbHotplugWatch third(other, 0x1209, 0x0001);
  EXPECT_EQ(second.registered(), third.registered());
}

TEST(UsbLink, MissingDeviceIsLinkClosedNamingVidPid) {
  try {
    connect_usb_link("usb:1209:0001");
    FAIL() << "connected to a device that is not there";
  } catch (const LinkClosed& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("usb:1209:0001"), std::string::npos) << message;
    EXPECT_NE(message.find("no such device"), std::string::npos) << message;
    EXPECT_NE(message.find("1209:0001"), std::string::npos) << message;
  }
}

TEST(UsbLink, MissingDeviceWithSerialNamesTheSerial) {
  try {
    connect_usb_link("usb:1209:0001:dome-7", 100ms);  // waits for an arrival that never comes
    FAIL() << "connected to a device that is not there";
  } catch (const LinkClosed& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("usb:1209:0001:dome-7"), std::string::npos) << message;
    EXPECT_NE(message.find("1209:0001"), std::string::npos) << message;
  }
}

#endif

TEST(UsbLink, MalformedUriFailsBeforeTouchingUsb) {
  if (!backend_built("usb")) GTEST_SKIP() << "built without libusb";
#ifdef LIGHTSTAGE_HAVE_LIBUSB
  EXPECT_THROW(connect_usb_link("usb:1209"), InputError);
#endif
}

}  // namespace
}  // namespace lightstage::hw

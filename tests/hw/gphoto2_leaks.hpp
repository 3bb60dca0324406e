#pragma once
// libgphoto2 2.5.30 leaks inside itself on every camera detection: its usb1
// port driver never frees the libusb device lists it asks for (while the
// port list loads, gp_port_info_list_load, and per driver in
// gp_port_usb_find_device), and the camera drivers it opens with libltdl and
// closes again leave their static initialisers' memory behind. A test
// binary that reaches gp_camera_autodetect (directly, or through
// hw::probe_devices()) includes this once, so that LeakSanitizer passes over
// exactly those two paths and still reports ours. Those libraries have no
// frame pointers: the suppressions only see their frames with the slow
// unwinder.

#if defined(__SANITIZE_ADDRESS__)
extern "C" const char* __lsan_default_suppressions() {
  return "leak:gp_port_info_list_load\n"
         "leak:gp_port_usb_find_device\n"
         "leak:lt_dlopenext\n";
}
extern "C" const char* __asan_default_options() { return "fast_unwind_on_malloc=0"; }
#endif

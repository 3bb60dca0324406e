#pragma once
// A V4L2 capture device in memory, behind hw::V4l2Syscalls: enough of the
// kernel's side (formats, controls, mmap buffers, the queue) for the v4l2:
// backend to run against. Tests script the frames the "sensor" produces and
// can unplug the device. poll() never sleeps: a frame is ready or it is not.

#include "lightstage/hw/pixel_formats.hpp"
#include "lightstage/hw/v4l2_camera.hpp"

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace lightstage::test {

class FakeV4l2Device final : public hw::V4l2Syscalls {
 public:
  struct Control {
    std::int32_t min = 0, max = 0, step = 1, def = 0, value = 0;
  };
  struct Frame {
    std::uint32_t sequence = 0;
    std::int64_t timestamp_ns = 0;
    std::vector<std::uint8_t> data;  // bytes as the driver writes them (stride included)
    bool error = false;              // V4L2_BUF_FLAG_ERROR
  };

  // --- the device as built
  std::string path = "/dev/video0";
  std::uint32_t capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  std::vector<std::pair<std::uint32_t, std::vector<std::pair<std::uint32_t, std::uint32_t>>>> formats = {
      {V4L2_PIX_FMT_GREY, {{640, 480}, {320, 240}}},
      {V4L2_PIX_FMT_Y10, {{640, 480}}},
      {V4L2_PIX_FMT_SRGGB12, {{640, 480}}},
      {V4L2_PIX_FMT_MJPEG, {{640, 480}}},  // one we cannot unpack: skipped
      {V4L2_PIX_FMT_YUYV, {{640, 480}}},
  };
  std::map<std::uint32_t, Control> controls;
  std::int64_t pixel_rate = 0;    // V4L2_CID_PIXEL_RATE, 0: absent
  std::uint32_t row_padding = 0;  // bytes added to every row (bytesperline)
  bool timestamps_monotonic = true;
  bool timestamps_soe = false;
  int open_errno = 0;  // non-zero: open() fails with it

  // --- state
  v4l2_pix_format fmt{};
  std::vector<std::vector<std::uint8_t>> buffers;
  std::deque<std::uint32_t> queued;
  bool streaming = false;
  bool unplugged = false;
  bool is_open = false;
  std::deque<Frame> sensor;      // frames the sensor will produce, one per queued buffer
  std::vector<std::string> log;  // the calls made, in order
  int mapped = 0;

  FakeV4l2Device() {
    fmt.width = 640;
    fmt.height = 480;
    fmt.pixelformat = V4L2_PIX_FMT_GREY;
    update_stride();
  }

  std::size_t row_bytes() const { return fmt.bytesperline; }

  // A frame of the current format whose every row is `row` (stride padding filled with 0xEE).
  Frame frame_of_rows(std::uint32_t sequence, std::int64_t timestamp_ns,
                      const std::vector<std::uint8_t>& row) const {
    Frame f{sequence, timestamp_ns, {}, false};
    for (std::uint32_t y = 0; y < fmt.height; ++y) {
      f.data.insert(f.data.end(), row.begin(), row.end());
      f.data.insert(f.data.end(), fmt.bytesperline - row.size(), 0xEE);
    }
    return f;
  }

  int open(const char* p, int) override {
    log.emplace_back("open");
    if (open_errno != 0) {
      errno = open_errno;
      return -1;
    }
    if (p != path) {
      errno = ENOENT;
      return -1;
    }
    is_open = true;
    return 42;
  }
  int close(int) override {
    log.emplace_back("close");
    is_open = false;
    return 0;
  }
  void* mmap(std::size_t length, int, int, int, off_t offset) override {
    const auto index = static_cast<std::size_t>(offset / kOffsetStep);
    if (index >= buffers.size() || length != buffers[index].size()) {
      errno = EINVAL;
      return MAP_FAILED;
    }
    ++mapped;
    return buffers[index].data();
  }
  int munmap(void*, std::size_t) override {
    --mapped;
    return 0;
  }
  int poll(pollfd* fds, nfds_t, int) override {
    fds[0].revents = 0;
    if (unplugged) {
      fds[0].revents = POLLERR;
      return 1;
    }
    if (streaming && !sensor.empty() && !queued.empty()) {
      fds[0].revents = POLLIN;
      return 1;
    }
    return 0;
  }

  int ioctl(int, unsigned long request, void* arg) override {
    switch (request) {
      case VIDIOC_QUERYCAP: {
        auto* cap = static_cast<v4l2_capability*>(arg);
        std::strcpy(reinterpret_cast<char*>(cap->driver), "fakecam");
        std::strcpy(reinterpret_cast<char*>(cap->card), "Fake Sensor");
        cap->capabilities = capabilities | V4L2_CAP_DEVICE_CAPS;
        cap->device_caps = capabilities;
        return 0;
      }
      case VIDIOC_ENUM_FMT: {
        auto* d = static_cast<v4l2_fmtdesc*>(arg);
        if (d->index >= formats.size()) return fail(EINVAL);
        d->pixelformat = formats[d->index].first;
        std::strcpy(reinterpret_cast<char*>(d->description), "fake format");
        return 0;
      }
      case VIDIOC_ENUM_FRAMESIZES: {
        auto* s = static_cast<v4l2_frmsizeenum*>(arg);
        for (const auto& [code, sizes] : formats) {
          if (code != s->pixel_format) continue;
          if (s->index >= sizes.size()) return fail(EINVAL);
          s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
          s->discrete.width = sizes[s->index].first;
          s->discrete.height = sizes[s->index].second;
          return 0;
        }
        return fail(EINVAL);
      }
      case VIDIOC_G_FMT: {
        static_cast<v4l2_format*>(arg)->fmt.pix = fmt;
        return 0;
      }
      case VIDIOC_S_FMT: {
        log.emplace_back("S_FMT");
        if (unplugged) return fail(ENODEV);
        if (streaming) return fail(EBUSY);
        auto& pix = static_cast<v4l2_format*>(arg)->fmt.pix;
        fmt.pixelformat = pix.pixelformat;
        fmt.width = pix.width;
        fmt.height = pix.height;
        update_stride();
        pix = fmt;
        return 0;
      }
      case VIDIOC_QUERYCTRL: {
        auto* q = static_cast<v4l2_queryctrl*>(arg);
        const auto it = controls.find(q->id);
        if (it == controls.end()) return fail(EINVAL);
        q->minimum = it->second.min;
        q->maximum = it->second.max;
        q->step = it->second.step;
        q->default_value = it->second.def;
        q->flags = 0;
        return 0;
      }
      case VIDIOC_G_CTRL: {
        auto* c = static_cast<v4l2_control*>(arg);
        const auto it = controls.find(c->id);
        if (it == controls.end()) return fail(EINVAL);
        c->value = it->second.value;
        return 0;
      }
      case VIDIOC_S_CTRL: {
        auto* c = static_cast<v4l2_control*>(arg);
        const auto it = controls.find(c->id);
        if (it == controls.end()) return fail(EINVAL);
        if (c->value < it->second.min || c->value > it->second.max) return fail(ERANGE);
        it->second.value = c->value;
        log.emplace_back("S_CTRL " + std::to_string(c->id) + "=" + std::to_string(c->value));
        return 0;
      }
      case VIDIOC_G_EXT_CTRLS: {
        auto* list = static_cast<v4l2_ext_controls*>(arg);
        if (list->count != 1 || list->controls[0].id != V4L2_CID_PIXEL_RATE || pixel_rate == 0)
          return fail(EINVAL);
        list->controls[0].value64 = pixel_rate;
        return 0;
      }
      case VIDIOC_REQBUFS: {
        auto* r = static_cast<v4l2_requestbuffers*>(arg);
        log.emplace_back("REQBUFS " + std::to_string(r->count));
        if (unplugged && r->count > 0) return fail(ENODEV);
        if (streaming) return fail(EBUSY);
        buffers.assign(r->count, std::vector<std::uint8_t>(fmt.sizeimage, 0));
        queued.clear();
        return 0;
      }
      case VIDIOC_QUERYBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        if (b->index >= buffers.size()) return fail(EINVAL);
        b->length = static_cast<std::uint32_t>(buffers[b->index].size());
        b->m.offset = b->index * kOffsetStep;
        return 0;
      }
      case VIDIOC_QBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        if (unplugged) return fail(ENODEV);
        if (b->index >= buffers.size()) return fail(EINVAL);
        queued.push_back(b->index);
        return 0;
      }
      case VIDIOC_DQBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        if (unplugged) return fail(ENODEV);
        if (!streaming || sensor.empty() || queued.empty()) return fail(EAGAIN);
        const Frame f = std::move(sensor.front());
        sensor.pop_front();
        const std::uint32_t index = queued.front();
        queued.pop_front();
        auto& mem = buffers[index];
        std::copy_n(f.data.begin(), std::min(f.data.size(), mem.size()), mem.begin());
        b->index = index;
        b->bytesused = static_cast<std::uint32_t>(std::min(f.data.size(), mem.size()));
        b->sequence = f.sequence;
        b->timestamp.tv_sec = f.timestamp_ns / 1'000'000'000;
        b->timestamp.tv_usec = (f.timestamp_ns % 1'000'000'000) / 1000;
        b->flags = (timestamps_monotonic ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_COPY) |
                   (timestamps_soe ? V4L2_BUF_FLAG_TSTAMP_SRC_SOE : V4L2_BUF_FLAG_TSTAMP_SRC_EOF) |
                   (f.error ? V4L2_BUF_FLAG_ERROR : 0);
        return 0;
      }
      case VIDIOC_STREAMON: {
        log.emplace_back("STREAMON");
        if (unplugged) return fail(ENODEV);
        if (queued.empty()) return fail(EINVAL);
        streaming = true;
        return 0;
      }
      case VIDIOC_STREAMOFF: {
        log.emplace_back("STREAMOFF");
        if (unplugged) return fail(ENODEV);
        streaming = false;
        queued.clear();
        return 0;
      }
      default:
        return fail(ENOTTY);
    }
  }

 private:
  static constexpr off_t kOffsetStep = 0x100000;

  static int fail(int err) {
    errno = err;
    return -1;
  }

  void update_stride() {
    const hw::PixelFormatDesc* desc = hw::find_v4l2_pixel_format(fmt.pixelformat);
    const std::size_t row = desc ? hw::min_row_bytes(desc->packing, static_cast<int>(fmt.width))
                                 : static_cast<std::size_t>(fmt.width) * 2;
    fmt.bytesperline = static_cast<std::uint32_t>(row + row_padding);
    fmt.sizeimage = fmt.bytesperline * fmt.height;
    fmt.field = V4L2_FIELD_NONE;
  }
};

}  // namespace lightstage::test

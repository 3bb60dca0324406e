#!/usr/bin/env python3
"""Writes the seed corpora of fuzz_sim_gpio (tests/fuzz/corpus/sim_gpio) and
fuzz_stack_images (tests/fuzz/corpus/stack_images).

sim_gpio: messages as a client of the sim's GPIO server sends them, encoded by
protoc, each as a 2-byte little-endian length and the payload (the fuzzer
frames them), optionally followed by raw bytes.
stack_images: one byte choosing the file replaced (0 the second PNG frame, 1
the mask, 2 the second PFM frame), then the file's bytes.
Run from anywhere: python3 tests/fuzz/make_input_corpora.py"""
import pathlib
import struct
import subprocess
import zlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
PROTO_DIR = ROOT / "common" / "proto"
CORPUS = ROOT / "tests" / "fuzz" / "corpus"

SIM_MESSAGES = {
    "chip_info": "request_id: 1 chip_info {}",
    "request_outputs": 'request_id: 2 request_lines { offsets: 0 offsets: 1 offsets: 100 output: true '
                       'consumer: "lightstage-domed" initial_values: 0 initial_values: 0 initial_values: 0 t_ns: 1000 }',
    "request_strobe": 'request_id: 3 request_lines { offsets: 101 output: false consumer: "strobe" }',
    "trigger_on": "request_id: 4 set_values { offsets: 100 values: 1 t_ns: 2000 }",
    "trigger_off": "request_id: 5 set_values { offsets: 100 values: 0 t_ns: 102000 }",
    "led_on": "request_id: 6 set_values { offsets: 0 offsets: 1 values: 1 values: 1 t_ns: 3000 }",
    "release": "request_id: 7 release_lines { offsets: 0 offsets: 1 offsets: 100 }",
    "stuck": 'request_id: 8 inject_fault { spec: "stuck:LED5" }',
    "drop": 'request_id: 9 inject_fault { spec: "drop-connection:2" }',
}


def encode(text):
    return subprocess.run(["protoc", "--encode=lightstage.proto.sim.ClientMessage", "-I", str(PROTO_DIR),
                           "lightstage/proto/sim_gpio.proto"],
                          input=text.encode(), capture_output=True, check=True, cwd=PROTO_DIR).stdout


def record(payload):
    return struct.pack("<H", len(payload)) + payload


def png(width, height, bit_depth=16, colour=0, rows=None):
    """A PNG file; rows=None gives a mid-grey image, rows=b'' a header-only file."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    header = chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, colour, 0, 0, 0))
    if rows is None:
        row = b"\0" + bytes([0x40, 0]) * (width * channels) if bit_depth == 16 else b"\0" + b"\x40" * width * channels
        rows = row * height
    data = chunk(b"IDAT", zlib.compress(rows)) if rows else b""
    return b"\x89PNG\r\n\x1a\n" + header + data + chunk(b"IEND", b"")


def pfm(width, height, values):
    return b"Pf\n%d %d\n-1\n" % (width, height) + b"".join(struct.pack("<f", v) for v in values)


def main():
    out = CORPUS / "sim_gpio"
    out.mkdir(parents=True, exist_ok=True)
    records = {name: record(encode(text)) for name, text in SIM_MESSAGES.items()}
    for name, data in records.items():
        (out / f"{name}.bin").write_bytes(data)
    session = ("chip_info", "request_outputs", "request_strobe", "led_on", "trigger_on", "trigger_off", "release")
    (out / "session.bin").write_bytes(b"".join(records[n] for n in session))
    (out / "faults.bin").write_bytes(b"".join(records[n] for n in ("request_outputs", "stuck", "drop", "led_on",
                                                                    "led_on", "chip_info")))
    (out / "garbage_tail.bin").write_bytes(records["chip_info"] + b"LS\xff\xff\xff\xff\r\nAT\r\n")

    out = CORPUS / "stack_images"
    out.mkdir(parents=True, exist_ok=True)
    (out / "frame_png.bin").write_bytes(b"\0" + png(4, 4))
    (out / "frame_png_rgb8.bin").write_bytes(b"\0" + png(4, 4, bit_depth=8, colour=2))
    (out / "frame_png_huge_header.bin").write_bytes(b"\0" + png(30000, 30000, rows=b""))
    (out / "frame_png_other_size.bin").write_bytes(b"\0" + png(5, 3))
    (out / "mask_png.bin").write_bytes(b"\1" + png(4, 4, bit_depth=8))
    (out / "frame_pfm.bin").write_bytes(b"\2" + pfm(4, 4, [0.5] * 16))
    (out / "frame_pfm_inf.bin").write_bytes(b"\2" + pfm(4, 4, [0.5] * 15 + [float("inf")]))
    (out / "frame_pfm_nan.bin").write_bytes(b"\2" + pfm(4, 4, [float("nan")] + [0.5] * 15))


if __name__ == "__main__":
    main()

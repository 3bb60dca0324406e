#!/usr/bin/env python3
"""Writes the seed corpus of fuzz_controller (tests/fuzz/corpus/controller):
host sessions as controller_fuzz.cpp reads them, records of [u16 LE header]
[bytes] (low 15 bits the length, top bit: send raw, else framed by the
target), each message encoded by protoc from the text below.
Run from anywhere: python3 tests/fuzz/make_controller_corpus.py"""
import pathlib
import struct
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]
PROTO_DIR = ROOT / "common" / "proto"
OUT = ROOT / "tests" / "fuzz" / "corpus" / "controller"

HELLO = 'request_id: 1 hello { protocol_version: 1 min_protocol_version: 1 client: "fuzz" watchdog_timeout_ms: 500 }'
STEPS = ("steps { leds { led_id: 0 level: 1 } settle_us: 200 trigger: true exposure_us: 1000 gap_us: 500 tag: 0 } "
         "steps { leds { led_id: 1 level: 1 } settle_us: 200 trigger: true wait_strobe: true strobe_timeout_us: 5000 gap_us: 500 tag: 1 } "
         "steps { leds { led_id: 2 level: 1 } leds { led_id: 3 level: 1 } settle_us: 100 exposure_us: 2000 gap_us: 100 tag: 2 }")
SESSIONS = {
    "run": [HELLO, f"request_id: 2 upload {{ sequence {{ id: 7 {STEPS} }} }}", "request_id: 3 run { sequence_id: 7 }",
            "heartbeat { counter: 1 }", "request_id: 4 status {}", "request_id: 5 abort {}"],
    "static": [HELLO, "request_id: 2 set_leds { leds { led_id: 1 level: 1 } leds { led_id: 2 level: 1 } }",
               "request_id: 3 status {}", "request_id: 4 set_leds { leds { led_id: 3 level: 1 } }",
               "request_id: 5 set_leds {}"],
    "refusals": ["request_id: 1 status {}", HELLO,
                 "request_id: 2 upload { sequence { id: 9 steps { leds { led_id: 0 level: 1 } exposure_us: 900000 } } }",
                 "request_id: 3 set_leds { leds { led_id: 77 level: 0.5 } }", "request_id: 4 run { sequence_id: 42 }",
                 "request_id: 5 upload { sequence { id: 10 } }"],
    "reupload": [HELLO, f"request_id: 2 upload {{ sequence {{ id: 1 {STEPS} }} }}",
                 f"request_id: 3 upload {{ sequence {{ id: 1 {STEPS} }} }}", "request_id: 4 run { sequence_id: 1 start_ns: 1 }",
                 "request_id: 5 set_leds { leds { led_id: 0 level: 1 } }", "request_id: 6 run { sequence_id: 1 }"],
}


def encode(text):
    return subprocess.run(["protoc", "--encode=lightstage.proto.HostMessage", "-I", str(PROTO_DIR),
                           "lightstage/proto/controller.proto"],
                          input=text.encode(), capture_output=True, check=True, cwd=PROTO_DIR).stdout


def record(payload, raw=False):
    return struct.pack("<H", len(payload) | (0x8000 if raw else 0)) + payload


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    for name, messages in SESSIONS.items():
        (OUT / f"{name}.bin").write_bytes(b"".join(record(encode(text)) for text in messages))
    # Garbage and a frame cut short between good messages.
    hello = encode(HELLO)
    cut = b"LS" + struct.pack("<I", 5000) + b"\x11" * 20
    noisy = (record(b"\x00garbage\r\n", raw=True) + record(hello) + record(cut, raw=True) +
             record(encode("request_id: 2 set_leds { leds { led_id: 0 level: 1 } }")) + record(b"") +
             record(encode("request_id: 3 status {}")))
    (OUT / "noisy.bin").write_bytes(noisy)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes the seed corpus of fuzz_protocol (tests/fuzz/corpus/protocol): real
frames of every message kind, encoded by protoc from the text below, framed as
common/framing.hpp says. Each file: one byte choosing the fuzzer's chunk size,
then the byte stream. Run from anywhere: python3 tests/fuzz/make_protocol_corpus.py"""
import pathlib
import struct
import subprocess
import zlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
PROTO_DIR = ROOT / "common" / "proto"
OUT = ROOT / "tests" / "fuzz" / "corpus" / "protocol"

HOST = ("lightstage/proto/controller.proto", "lightstage.proto.HostMessage")
CONTROLLER = ("lightstage/proto/controller.proto", "lightstage.proto.ControllerMessage")
SIM_CLIENT = ("lightstage/proto/sim_gpio.proto", "lightstage.proto.sim.ClientMessage")
SIM_SERVER = ("lightstage/proto/sim_gpio.proto", "lightstage.proto.sim.ServerMessage")

MESSAGES = {
    "hello": (HOST, 'request_id: 1 hello { protocol_version: 1 min_protocol_version: 1 client: "lightstage 0.1.0" watchdog_timeout_ms: 500 }'),
    "set_leds": (HOST, "request_id: 2 set_leds { leds { led_id: 3 level: 1 } leds { led_id: 17 level: 0.5 } }"),
    "upload": (HOST, "request_id: 3 upload { sequence { id: 7 "
               "steps { leds { led_id: 0 level: 1 } settle_us: 200 trigger: true exposure_us: 10000 gap_us: 500 tag: 0 } "
               "steps { leds { led_id: 1 level: 1 } settle_us: 200 trigger: true wait_strobe: true strobe_timeout_us: 50000 gap_us: 500 tag: 1 } } }"),
    "run": (HOST, "request_id: 4 run { sequence_id: 7 start_ns: 123456789000 }"),
    "abort": (HOST, "request_id: 5 abort {}"),
    "status": (HOST, "request_id: 6 status {}"),
    "heartbeat": (HOST, "heartbeat { counter: 42 }"),
    "info": (CONTROLLER, 'request_id: 1 info { protocol_version: 1 firmware_version: "0.1.0" rig_name: "sim-dome" led_count: 2 '
             "leds { id: 0 max_on_us: 100000 max_duty: 0.5 duty_window_us: 1000000 } "
             "capabilities { strobe_input: true max_sequence_steps: 4096 watchdog_timeout_ms: 500 max_watchdog_timeout_ms: 5000 } "
             'gpio_uri: "sim:/run/lightstage/sim.sock" clock_ns: 99 }'),
    "step_event": (CONTROLLER, "step_event { sequence_id: 7 step: 1 tag: 1 led_ids: 1 planned_start_ns: 1000 leds_on_ns: 1010 "
                   "trigger_ns: 1210 trigger_end_ns: 1260 strobe_rise_ns: 1300 strobe_fall_ns: 11300 leds_off_ns: 11310 "
                   "lateness_ns: 10 outcome: OK }"),
    "sequence_done": (CONTROLLER, 'sequence_done { sequence_id: 7 steps_run: 2 outcome: STROBE_TIMEOUT detail: "step 1" max_lateness_ns: 52000 }'),
    "error": (CONTROLLER, 'request_id: 9 error { code: MALFORMED_FRAME message: "frame failed its CRC" }'),
    "sim_request_lines": (SIM_CLIENT, 'request_id: 1 request_lines { offsets: 0 offsets: 1 offsets: 100 output: true consumer: "lightstage-domed" initial_values: 0 initial_values: 0 initial_values: 0 }'),
    "sim_set_values": (SIM_CLIENT, "request_id: 2 set_values { offsets: 0 values: 1 t_ns: 123456 }"),
    "sim_edge": (SIM_SERVER, "edge { offset: 101 rising: true t_ns: 123999 }"),
}


def encode(kind, text):
    proto, message = kind
    return subprocess.run(["protoc", f"--encode={message}", "-I", str(PROTO_DIR), proto],
                          input=text.encode(), capture_output=True, check=True, cwd=PROTO_DIR).stdout


def frame(payload):
    return b"LS" + struct.pack("<I", len(payload)) + payload + struct.pack("<I", zlib.crc32(payload) & 0xFFFFFFFF)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    frames = {name: frame(encode(kind, text)) for name, (kind, text) in MESSAGES.items()}
    for index, (name, data) in enumerate(frames.items()):
        (OUT / f"{name}.bin").write_bytes(bytes([index % 64]) + data)
    # A session as a host sends it, in one stream.
    session = b"".join(frames[n] for n in ("hello", "upload", "run", "heartbeat", "status", "abort"))
    (OUT / "session.bin").write_bytes(bytes([0]) + session)
    # Garbage, a frame with a flipped payload bit, an oversize length, then good frames.
    damaged = bytearray(frames["set_leds"])
    damaged[8] ^= 0x01
    noisy = b"\r\nAT\r\n" + bytes(damaged) + b"LS\xff\xff\xff\xff" + frames["heartbeat"] + b"L" + frames["status"]
    (OUT / "noisy.bin").write_bytes(bytes([5]) + noisy)


if __name__ == "__main__":
    main()

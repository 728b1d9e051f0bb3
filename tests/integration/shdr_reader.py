#!/usr/bin/python3
"""shdr_reader: an independent MTConnect SHDR reader for the tests.

Reads an adapter the way an MTConnect agent does, from the protocol as the
standard describes it, with none of the project's code: the device file
(Devices.xml) says which data items exist and which are conditions; each
line is "timestamp|key|value[|key|value...]" for events and samples, and
"timestamp|key|level|native_code|native_severity|qualifier|message" for a
condition; keys may carry the device ("device:name"); "* PING" is answered
"* PONG <heartbeat ms>".

  shdr_reader.py --port P --devices Devices.xml [--duration S] [--ping-s S]

Prints one JSON object per observation (recv: the wall clock when the line
arrived; ts: the line's timestamp, both in Unix seconds) and one per PONG.
Unknown keys and malformed lines are reported as {"error": ...} (an agent
discards them). Exit status 0 after --duration, 1 when the adapter closes
the connection first.
"""
import argparse
import datetime
import json
import socket
import sys
import time
import xml.etree.ElementTree as ET


def load_devices(path):
    """(device name, data item name) -> category, from the device file."""
    items = {}
    root = ET.parse(path).getroot()
    for dev in root.iter():
        if not dev.tag.endswith("}Device") and dev.tag != "Device":
            continue
        name = dev.get("name")
        for di in dev.iter():
            if di.tag.endswith("DataItem"):
                items[(name, di.get("name"))] = di.get("category")
                items[(name, di.get("id"))] = di.get("category")
    return items


def parse_time(text):
    t = text.rstrip("Z")
    return datetime.datetime.fromisoformat(t).replace(
        tzinfo=datetime.timezone.utc).timestamp()


def emit(obj):
    print(json.dumps(obj), flush=True)


def handle(line, items, recv):
    if line.startswith("* PONG"):
        emit({"recv": recv, "pong": int(line.split()[2])})
        return
    if line.startswith("*"):
        return  # other protocol commands
    fields = line.split("|")
    try:
        ts = parse_time(fields[0])
    except ValueError:
        emit({"error": "bad timestamp", "line": line})
        return
    i = 1
    while i < len(fields):
        key = fields[i]
        device, _, name = key.rpartition(":")
        category = items.get((device, name))
        if category is None:
            emit({"error": "unknown data item", "key": key, "line": line})
            return
        if category == "CONDITION":
            if len(fields) < i + 6:
                emit({"error": "short condition", "line": line})
                return
            level, code, severity, qualifier, message = fields[i + 1:i + 6]
            emit({"recv": recv, "ts": ts, "device": device, "item": name, "condition": level,
                  "native_code": code, "native_severity": severity, "qualifier": qualifier,
                  "message": message})
            i += 6
        else:
            if len(fields) < i + 2:
                emit({"error": "key without value", "line": line})
                return
            emit({"recv": recv, "ts": ts, "device": device, "item": name,
                  "value": fields[i + 1]})
            i += 2


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--devices", required=True)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--ping-s", type=float, default=1.0)
    args = ap.parse_args()
    items = load_devices(args.devices)
    sock = socket.create_connection((args.host, args.port), timeout=5)
    sock.settimeout(0.05)
    buf = b""
    t0 = time.time()
    next_ping = t0
    while time.time() - t0 < args.duration:
        if time.time() >= next_ping:
            sock.sendall(b"* PING\n")
            next_ping += args.ping_s
        try:
            data = sock.recv(65536)
        except socket.timeout:
            continue
        if not data:
            emit({"error": "adapter closed the connection"})
            return 1
        recv = time.time()
        buf += data
        while b"\n" in buf:
            line, buf = buf.split(b"\n", 1)
            handle(line.decode().rstrip("\r"), items, recv)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Writes the committed hostile seeds of fuzz/seeds/<target>/ (issue #20's attacks as files).

Run from the repository root: python3 fuzz/seeds/make_seeds.py. The seeds taken as they are
from datasets/ (budgets, the golden blob, HEX and calibration) are copied by fuzz/run.sh and
not duplicated here; the saved reports in fuzz/seeds/report_fuzz/ were written by
`characterize` (see fuzz/seeds/README.md).
"""
import copy
import json
import os
import shutil
import sqlite3
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)))


def write(target, name, data):
    d = os.path.join(ROOT, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def deep(n):
    # ~n levels of nesting, the shape of the 70,000-level report that overflowed the stack,
    # cut to what fits the targets' -max_len.
    return '{"schema":"x","a":' + "[" * n + "]" * n + "}"


def hex_record(address16, rtype, payload):
    body = bytes([len(payload), address16 >> 8, address16 & 0xFF, rtype]) + payload
    checksum = (-sum(body)) & 0xFF
    return ":" + (body + bytes([checksum])).hex().upper() + "\n"


def main():
    # Budgets (characterize budget, --budget, --reference-u).
    with open("datasets/budgets/gum_h1_end_gauge.json") as f:
        gauge = json.load(f)
    b = copy.deepcopy(gauge)
    b["measurand"]["model"] = "ls=5"  # a muparser assignment, issue #20
    write("budget_fuzz", "model_assignment.json", json.dumps(b))
    b = copy.deepcopy(gauge)
    b["inputs"][0]["u"] = 1e308
    b["inputs"][1]["value"] = 1e308
    write("budget_fuzz", "overflow_1e308.json", json.dumps(b))
    b = copy.deepcopy(gauge)
    b["monte_carlo"] = {"adaptive": True, "max_trials": 1e15, "ndig": 6}
    write("budget_fuzz", "max_trials_1e15.json", json.dumps(b))
    b = copy.deepcopy(gauge)
    b["correlations"] = [{"a": "ls", "b": "d0", "r": 1.5}, {"a": "ls", "b": "ls", "r": 1}]
    write("budget_fuzz", "bad_correlations.json", json.dumps(b))
    write("budget_fuzz", "deep_nesting.json", deep(4000))

    # Tag registry (--tag-registry).
    write("tag_registry_fuzz", "registry.json",
          json.dumps({"1": "Forehead", "2": "Chest", "16": "Spare tag"}))
    write("tag_registry_fuzz", "control_chars.json",
          json.dumps({"1": "\x1b]0;owned\x07\x1b[2J", "2": "two\nlines\r", "3": ""}))
    write("tag_registry_fuzz", "bad_keys.json",
          '{"-1": "a", "0": "b", "1e3": "c", "99999999999999999999": "d", "": "e", " 7": "f"}')
    write("tag_registry_fuzz", "wrong_types.json", '{"1": 5, "2": null, "3": ["x"], "4": {}}')
    write("tag_registry_fuzz", "not_object.json", "[1, 2, 3]")
    write("tag_registry_fuzz", "deep_nesting.json", deep(4000))

    # calibration.json: the golden file with the bulky per-segment arrays cut short.
    with open("datasets/golden/calibration_sensor2.json") as f:
        cal = json.load(f)
    for tag in cal["tags"]:
        tag["segments_found"] = tag["segments_found"][:2]
        for sensor in ("accel", "gyro"):
            tag[sensor]["segments"] = tag[sensor]["segments"][:2]
    write("calibration_fuzz", "golden_small.json", json.dumps(cal))
    c = copy.deepcopy(cal)
    c["tags"][0]["accel"]["matrix"][0][0] *= 2  # disagrees with scale/misalignment
    write("calibration_fuzz", "matrix_mismatch.json", json.dumps(c))
    c = copy.deepcopy(cal)
    c["tags"][0]["gyro"]["bias"] = [1e308, -1e308, 1e308]
    c["tags"][0]["accel"]["bias_u"] = [-1, 0, 1e308]
    write("calibration_fuzz", "huge_numbers.json", json.dumps(c))
    c = copy.deepcopy(cal)
    del c["tags"][0]["gyro"]
    c["tags"].append(copy.deepcopy(c["tags"][0]))  # the same sensor twice
    write("calibration_fuzz", "duplicate_tag.json", json.dumps(c))
    write("calibration_fuzz", "deep_nesting.json", deep(4000))

    # Saved reports (characterize report): the calibration certificate and hostile JSON.
    write("report_fuzz", "calibration_small.json", json.dumps(cal))
    write("report_fuzz", "deep_nesting.json", deep(4000))
    write("report_fuzz", "generic_budget.json",
          json.dumps({"schema": "metro.other/1", "budget": [{"name": "<script>", "u": 1e308},
                                                             {"name": "x", "u": -1}],
                      "rows": [[1, 2], {"a": None}]}))
    write("report_fuzz", "wrong_schema_types.json",
          json.dumps({"schema": "metro.report/1", "tags": 5, "input": []}))

    # Intel HEX and inspect: the golden image with hostile additions (issue #20, part 1).
    with open("datasets/golden/tag_sensor2.hex") as f:
        lines = f.read().splitlines(keepends=True)
    eof = lines[-1]
    body = lines[:-1]
    mbr = hex_record(0, 4, b"\x00\x00") + hex_record(0, 0, bytes(range(16)))
    boot = hex_record(0, 4, b"\x00\x03") + hex_record(0xC000, 0, b"\xAA" * 16)
    near = hex_record(0, 4, b"\x00\x03") + hex_record(0xB800, 0, b"\x55" * 16)
    for target in ("intel_hex_fuzz", "inspect_fuzz"):
        write(target, "outside_mbr.hex", "".join(body) + mbr + eof)
        write(target, "outside_bootloader.hex", "".join(body) + boot + eof)
        write(target, "outside_3b800.hex", "".join(body) + near + eof)
        write(target, "no_tombstone.hex",
              "".join(l for l in body if not l.startswith(":04B40000")) + eof)
        write(target, "after_eof.hex", "".join(body) + eof + body[1])
        write(target, "record_02.hex", hex_record(0, 2, b"\x10\x00") + "".join(body) + eof)
        write(target, "crlf_lower.hex", "".join(body).lower().replace("\n", "\r\n") + eof)
    with open("datasets/golden/tag_sensor2.bin", "rb") as f:
        blob = f.read()
    write("inspect_fuzz", "trailing_data.bin", blob + b"\x00" * 200)
    write("inspect_fuzz", "header_only.bin", blob[:32])
    nan = bytearray(blob)
    nan[64:72] = struct.pack("<d", float("nan"))
    write("inspect_fuzz", "nan_constant.bin", bytes(nan))

    # The calibration registry (--registry, issue #37): variants of line.sqlite, a registry
    # written by `calibrate blob` (fuzz/seeds/README.md), with the values the re-attack used.
    registry_variants = {
        "schema_abc.sqlite": ["UPDATE schema_version SET version = 'abc'"],
        "schema_huge.sqlite": ["UPDATE schema_version SET version = 99999999999"],
        "schema_minus1.sqlite": ["UPDATE schema_version SET version = -1"],
        "schema_two_rows.sqlite": ["INSERT INTO schema_version (version) VALUES (2)"],
        "schema_v1.sqlite": ["UPDATE schema_version SET version = 1"],
        "blob_seq_text.sqlite": ["UPDATE blobs SET seq = 'abc', crc = 99999999999"],
        "constant_inf.sqlite": ["UPDATE constants SET u = 1e999 WHERE name = 'accel.b_x'"],
        "device_not_hex.sqlite": ["UPDATE device_calibrations SET device_id = 'zz'"],
        "covariance_not_json.sqlite": ["UPDATE calibrations SET covariance_json = '{'"],
        "foreign.sqlite": None,
    }
    base = os.path.join(ROOT, "registry_fuzz", "line.sqlite")
    for name, statements in registry_variants.items():
        path = os.path.join(ROOT, "registry_fuzz", name)
        if os.path.exists(path):
            os.remove(path)
        if statements is None:
            db = sqlite3.connect(path)
            db.execute("PRAGMA page_size = 512")
            db.execute("CREATE TABLE parts (id INTEGER PRIMARY KEY, name TEXT)")
            db.execute("INSERT INTO parts (name) VALUES ('gear')")
        else:
            shutil.copyfile(base, path)
            db = sqlite3.connect(path)
            for sql in statements:
                db.execute(sql)
        db.commit()
        db.execute("VACUUM")
        db.close()


if __name__ == "__main__":
    main()

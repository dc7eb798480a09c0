#!/usr/bin/env python3
"""Writes test_dfreader.json: what pymavlink's own DataFlash reader (DFReader.py, an
independent reader) finds in test.BIN: every message name's count, and every IMU and IMU2
message's TimeUS, GyrX..GyrZ, AccX..AccZ and T (floats as Python's shortest round-trip text).

Usage: dump_dfreader.py PYMAVLINK_CHECKOUT test.BIN > test_dfreader.json
PYMAVLINK_CHECKOUT is a checkout of github.com/ArduPilot/pymavlink (SOURCE.md names the
commit); its DFReader.py and dfindexer/__init__.py are imported from there, unchanged (the
Cython indexer is not built: DFReader falls back to its Python indexer). DFReader's only
uses of mavutil on this file are given here: the MAV_TYPE constants of MAVLink's common.xml,
evaluate_condition for no condition, and no flight-mode table (MODE messages read as
'UNKNOWN' mode, which nothing here uses)."""
import collections
import importlib.util
import json
import os
import sys
import types


def main(checkout, path):
    package = types.ModuleType("pymavlink")
    package.__path__ = []
    sys.modules["pymavlink"] = package
    mavutil = types.ModuleType("pymavlink.mavutil")
    mavutil.mavlink = types.SimpleNamespace(
        MAV_TYPE_GENERIC=0, MAV_TYPE_FIXED_WING=1, MAV_TYPE_QUADROTOR=2, MAV_TYPE_HELICOPTER=4,
        MAV_TYPE_ANTENNA_TRACKER=5, MAV_TYPE_AIRSHIP=7, MAV_TYPE_GROUND_ROVER=10,
        MAV_TYPE_SUBMARINE=12)
    mavutil.evaluate_condition = lambda condition, variables: condition is None
    mavutil.mode_mapping_bynumber = lambda mav_type: None
    sys.modules["pymavlink.mavutil"] = mavutil
    package.mavutil = mavutil
    for name, rel in (("dfindexer", "dfindexer/__init__.py"), ("DFReader", "DFReader.py")):
        spec = importlib.util.spec_from_file_location(
            "pymavlink." + name, os.path.join(checkout, rel),
            submodule_search_locations=[] if name == "dfindexer" else None)
        module = importlib.util.module_from_spec(spec)
        sys.modules["pymavlink." + name] = module
        setattr(package, name, module)
        spec.loader.exec_module(module)
    reader = sys.modules["pymavlink.DFReader"].DFReader_binary(path, zero_time_base=False)
    counts = collections.Counter()
    imu = collections.defaultdict(list)
    while True:
        m = reader.recv_msg()
        if m is None:
            break
        counts[m.get_type()] += 1
        if m.get_type() in ("IMU", "IMU2", "IMU3"):
            d = m.to_dict()
            imu[m.get_type()].append([d[k] for k in ("TimeUS", "GyrX", "GyrY", "GyrZ", "AccX",
                                                      "AccY", "AccZ", "T")])
    out = {"reader": "pymavlink DFReader.DFReader_binary", "file": os.path.basename(path),
           "counts": dict(sorted(counts.items())),
           "imu_columns": ["TimeUS", "GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ", "T"],
           "imu": imu}
    json.dump(out, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

#!/usr/bin/env python3
"""Writes the committed seeds of firmware/fuzz/seeds/ (the blob fuzzer's corpus start).

Run from the repository root: python3 firmware/fuzz/make_seeds.py. Each seed is the golden blob
(datasets/golden/tag_sensor2.bin, written by the C++ side; firmware/fuzz/run.sh copies it too)
with its GYRO section turned into a section v2.0 (issue #25, docs/calibration-blob.md 2.4:
byte 3 the input encoding, the u32 at body offset 172 the declared s_nom), CRC resealed:
accepted ones, so the fuzzer starts inside the v2.0 decoder and limit checks, and hostile ones
next to each of its rules.
"""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
GYRO_SECTION = 0x160  # the v1 map: GYRO section header; body at 0x168
GYRO_BODY = GYRO_SECTION + 8


def reseal(blob):
    total = struct.unpack_from("<H", blob, 8)[0]
    struct.pack_into("<I", blob, total - 4, zlib.crc32(bytes(blob[: total - 4])) & 0xFFFFFFFF)
    return blob


def v2(golden, s_nom, input_code, m_scale=1.0, version=0x0200):
    b = bytearray(golden)
    struct.pack_into("<H", b, GYRO_SECTION + 2, version)
    b[GYRO_BODY + 3] = input_code
    struct.pack_into("<f", b, GYRO_BODY + 172, s_nom)
    for i in range(9):
        (m,) = struct.unpack_from("<f", b, GYRO_BODY + 8 + 4 * i)
        struct.pack_into("<f", b, GYRO_BODY + 8 + 4 * i, m * m_scale)
    return bytes(reseal(b))


def write(name, data):
    os.makedirs(os.path.join(HERE, "seeds"), exist_ok=True)
    with open(os.path.join(HERE, "seeds", name), "wb") as f:
        f.write(data)


def main():
    with open("datasets/golden/tag_sensor2.bin", "rb") as f:
        golden = f.read()
    s_fs0 = 250.0 / 32768.0 * 3.141592653589793 / 180.0  # the golden gyro is at fs_sel 0
    xsens = 3.141592653589793 / 180.0 / 83.2  # imu_tk's Xsens gyroscope, 83.2 LSB/(deg/s)
    write("v2_gyro_int16.bin", v2(golden, s_fs0, 0))
    write("v2_gyro_offset_binary.bin", v2(golden, s_fs0, 1))
    write("v2_gyro_xsens_83lsb.bin", v2(golden, xsens, 1, m_scale=131.072 / 83.2))
    write("v2_gyro_s_nom_edge.bin", v2(golden, 2.0 ** -14, 1, m_scale=2.0 ** -14 / s_fs0))
    write("v2_1_gyro.bin", v2(golden, s_fs0, 1, version=0x0201))
    # hostile: s_nom NaN, 2^-7 (outside), M 27 % off its s_nom, input code 2
    write("v2_gyro_s_nom_nan.bin", v2(golden, float("nan"), 0))
    write("v2_gyro_s_nom_2e-7.bin", v2(golden, 2.0 ** -7, 0, m_scale=2.0 ** -7 / s_fs0))
    write("v2_gyro_m_27pct.bin", v2(golden, s_fs0, 0, m_scale=1.27))
    write("v2_gyro_input_2.bin", v2(golden, s_fs0, 2))


if __name__ == "__main__":
    main()

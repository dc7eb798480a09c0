# The Python module against the characterize program: the same library calls, so the same bytes.
# Every comparison below runs the CLI on a bundled dataset and the module on the same input.
import json
import math
import os
import signal
import threading
import time

import numpy as np
import pytest

import metro
from conftest import DATASETS, run_cli

STATIC = DATASETS / "static_imu_100hz.csv"  # metro simulate, 60 s at 100 Hz
CHEST = DATASETS / "static_chest.csv"
RECEIVER = DATASETS / "static_chest_receiver.txt"
EUROC = DATASETS / "external" / "euroc_v1_01_easy_imu0_kimera" / "data.csv"
BUDGETS = DATASETS / "budgets"


def cli_json(cli, *args):
    code, out, err = cli(*args)
    assert code == 0, err
    return out.decode()


# --- Reports: byte for byte -------------------------------------------------------------------

@pytest.mark.parametrize("path", [STATIC, CHEST, RECEIVER, EUROC], ids=lambda p: p.name)
def test_type_a_equals_cli(cli, path):
    expected = cli_json(cli, path, "--type-a")
    assert metro.type_a(str(path)).to_json() == expected
    # A loaded session gives the same report.
    assert metro.type_a(metro.load(path)).to_json() == expected


EXTERNAL = DATASETS / "external"


@pytest.mark.parametrize("path, cli_args, load_kwargs", [
    (EXTERNAL / "px4_pyulog_samples" / "sample.ulg", [], {}),
    (EXTERNAL / "ros_samples" / "imu_lz4.mcap", [], {}),
    (EXTERNAL / "ros_samples" / "two_imus_zstd.mcap", ["--topic", "/imu1"], {"topics": ["/imu1"]}),
    (EXTERNAL / "ros_samples" / "ros1_lz4.bag", [], {}),
    (EXTERNAL / "ros_samples" / "rosbag2_sqlite", [], {}),
    (EXTERNAL / "ardupilot_pymavlink_test_bin" / "test.BIN", ["--lenient"], {"lenient": True}),
    (EXTERNAL / "mpu6050_imucalibration_static_7min" / "example_data_tinit_calc.csv", [], {}),
], ids=lambda v: v.name if hasattr(v, "name") else None)
def test_other_formats_equal_cli(cli, path, cli_args, load_kwargs):
    expected = cli_json(cli, path, "--type-a", *cli_args)
    assert metro.type_a(metro.load(path, **load_kwargs)).to_json() == expected


def test_format_errors_equal_cli(cli):
    path = EXTERNAL / "ros_samples" / "two_imus_zstd.mcap"
    code, _, err = cli(path, "--type-a")
    assert code == 2
    with pytest.raises(metro.InputError) as e:
        metro.load(path)
    assert err == f"error: {e.value}\n"


def test_type_a_allan_settle_equals_cli(cli):
    expected = cli_json(cli, STATIC, "--type-a", "--allan", "--settle", "auto", "--taus", "decade:5")
    report = metro.type_a(STATIC, allan=True, settle="auto", taus="decade:5")
    assert report.to_json() == expected
    assert report.to_dict() == json.loads(expected)


def test_window_and_selection_equal_cli(cli):
    expected = cli_json(cli, EUROC, "--type-a", "--from-s", "10", "--to-s", "50", "--quantity",
                        "gx_rads", "--quantity", "az_mps2")
    got = metro.type_a(EUROC, from_s=10, to_s=50, quantities=["gx_rads", "az_mps2"]).to_json()
    assert got == expected


@pytest.mark.parametrize("name", ["gum_h1_end_gauge.json", "jcgm101_9_2_2_additive.json",
                                  "fingertip_chord.json"])
def test_budget_equals_cli(cli, name):
    path = BUDGETS / name
    expected = cli_json(cli, "budget", path)
    result = metro.budget(str(path))
    assert result.to_json() == expected
    d = json.loads(expected)
    assert result.value == d["result"]["value"] and result.u == d["result"]["u"]


def test_budget_from_dict_equals_file(cli):
    path = BUDGETS / "gum_h1_end_gauge.json"
    expected = json.loads(cli_json(cli, "budget", path))
    got = metro.budget(json.loads(path.read_text())).to_dict()
    # Only the name of the budget differs: a dict has no file.
    assert got.pop("budget_file") == "<dict>"
    expected.pop("budget_file")
    assert got == expected


def test_allan_of_array_equals_cli_section(cli):
    """metro.allan on a tag's samples at the CLI's tau0 gives the CLI's curve and terms."""
    report = json.loads(cli_json(cli, STATIC, "--type-a", "--allan", "--quantity", "gx_dps"))
    section = report["sensors"][0]["quantities"]["gx_dps"]["allan"]
    tau0 = section["sample_period"]["tau0_s"]
    x = metro.load(STATIC).tag(1)["gx_dps"]
    got = metro.allan(np.ascontiguousarray(x), tau0, unit="deg/s").to_dict()
    for key in ("sample_period",):  # From the timestamps, which metro.allan is not given.
        section.pop(key)
        got.pop(key)
    assert got == section
    a = metro.allan(np.ascontiguousarray(x), tau0, unit="deg/s")
    assert a.tau_s.tolist() == section["tau_s"] and a.adev.tolist() == section["adev"]
    assert a.noise["random_walk"].value == section["noise"]["random_walk"]["value"]


def test_report_type_a_accessor(cli):
    expected = json.loads(cli_json(cli, CHEST, "--type-a"))
    report = metro.type_a(CHEST)
    for sensor in expected["sensors"]:
        names = report.quantities(sensor["sensor"])
        assert names == list(sensor["quantities"])
        for name in names:
            want = sensor["quantities"][name]["type_a"]
            got = report.type_a(name, sensor=sensor["sensor"])
            assert (got.n, got.mean, got.std) == (want["n"], want["mean"], want["std"])
            assert got.u_mean == want["u_mean"] or (want["u_mean"] is None and math.isnan(got.u_mean))
    with pytest.raises(KeyError, match="sensor 99"):
        report.type_a("pitch_deg", sensor=99)
    with pytest.raises(KeyError, match="nope_deg: not in the report"):
        report.type_a("nope_deg")


def test_report_allan_accessor(cli):
    report = metro.type_a(STATIC, allan=True, quantities=["gz_dps"])
    a = report.allan("gz_dps", sensor=1)
    d = report.to_dict()["sensors"][0]["quantities"]["gz_dps"]["allan"]
    assert a.adev.tolist() == d["adev"]
    assert np.all(a.ci_low <= a.adev) and np.all(a.adev <= a.ci_high)


def test_allan_white_noise_closed_form():
    """White rate noise of sigma: oadev(tau0) = sigma, and N = sigma sqrt(tau0) (IEEE 952 Annex C)."""
    rng = np.random.default_rng(7)
    sigma, tau0 = 0.05, 0.01
    x = rng.normal(0.0, sigma, 200_000)
    a = metro.allan(x, tau0, unit="deg/s")
    # At m = 1 the EDF is about N: a relative standard deviation near 1 / sqrt(2 N) = 0.16 %.
    assert a.tau_s[0] == tau0 and abs(a.adev[0] / sigma - 1) < 0.01
    assert a.ci_low[0] < a.adev[0] < a.ci_high[0] and a.edf[0] > 1e5
    n = a.noise["random_walk"]
    assert n.unit == "deg/s*sqrt(s)" and abs(n.value - sigma * math.sqrt(tau0)) < 3 * n.u


# --- Arrays: zero copy, read-only views -------------------------------------------------------

def test_allan_reads_the_array_in_place():
    x = np.random.default_rng(1).normal(size=10_000)
    a = metro.allan(x, 0.01)
    assert a.input_address == x.__array_interface__["data"][0]


def test_session_views_share_memory_and_outlive_the_session():
    tag = metro.load(STATIC).tag(1)  # The session object itself is dropped here.
    t1, t2 = tag.t_s, tag.t_s
    assert np.shares_memory(t1, t2)
    assert not t1.flags.writeable
    with pytest.raises(ValueError):
        t1[0] = 1.0
    del tag
    assert t1.size == 6000 and t1[1] == pytest.approx(0.01)


def test_from_arrays_equals_loaded_session():
    s = metro.load(STATIC)
    tag = s.tag(1)
    columns = {name: np.array(v) for name, v in tag.quantities.items()}
    built = metro.Session.from_arrays(np.array(tag.t_s), columns)
    a = metro.type_a(built).to_dict()["sensors"][0]["quantities"]
    b = metro.type_a(s).to_dict()["sensors"][0]["quantities"]
    for name in columns:
        assert a[name]["type_a"] == b[name]["type_a"], name


def test_from_arrays_derives_euler_as_the_loaders(tmp_path):
    # Quaternions (w, x, y, z) of known z-y-x angles, q = q_z(yaw) q_y(pitch) q_x(roll)
    # (include/metro/core/angles.hpp, thesis eq. 4.41), in closed form.
    rng = np.random.default_rng(7)
    n = 50
    yaw, pitch, roll = rng.uniform(-170, 170, n), rng.uniform(-80, 80, n), rng.uniform(-170, 170, n)
    cy, sy = np.cos(np.radians(yaw) / 2), np.sin(np.radians(yaw) / 2)
    cp, sp = np.cos(np.radians(pitch) / 2), np.sin(np.radians(pitch) / 2)
    cr, sr = np.cos(np.radians(roll) / 2), np.sin(np.radians(roll) / 2)
    q = {"qw": cr * cp * cy + sr * sp * sy, "qx": sr * cp * cy - cr * sp * sy,
         "qy": cr * sp * cy + sr * cp * sy, "qz": cr * cp * sy - sr * sp * cy}
    t = np.arange(n) * 0.01
    built = metro.Session.from_arrays(t, {**q, "gx_dps": rng.normal(size=n)}).tag()
    for name, truth in [("yaw_deg", yaw), ("pitch_deg", pitch), ("roll_deg", roll)]:
        assert built.units[name] == "deg"
        np.testing.assert_allclose(built[name], truth, atol=1e-9)
    # The same rows as a session.csv: metro.load derives the same angles, bit for bit.
    path = tmp_path / "q.csv"
    rows = ["t_s,sensor,qw,qx,qy,qz,gx_dps"] + [
        ",".join(repr(float(v)) if k != 1 else "1" for k, v in enumerate(
            [t[i], 1, q["qw"][i], q["qx"][i], q["qy"][i], q["qz"][i], built["gx_dps"][i]]))
        for i in range(n)]
    path.write_text("\n".join(rows) + "\n")
    loaded = metro.load(path).tag()
    assert list(loaded.quantities) == list(built.quantities)
    for name in ["yaw_deg", "pitch_deg", "roll_deg"]:
        assert np.array_equal(loaded[name], built[name]), name
    # Given angles are kept; quaternions far from unit norm are derived with the loaders' warning.
    given = metro.Session.from_arrays(t, {**q, "yaw_deg": np.zeros(n)}).tag()
    assert "pitch_deg" not in given.quantities and not given["yaw_deg"].any()
    with pytest.warns(RuntimeWarning, match="50 of 50 quaternions have a norm more than"):
        scaled = metro.Session.from_arrays(t, {k: 2 * v for k, v in q.items()}).tag()
    np.testing.assert_allclose(scaled["yaw_deg"], yaw, atol=1e-9)


# --- Bad input --------------------------------------------------------------------------------

@pytest.mark.parametrize("bad, what", [
    (np.arange(100, dtype=np.float32), "dtype float32"),
    (np.arange(100), "dtype int64"),
    (np.zeros((10, 10)), "2 dimensions"),
    (np.zeros(200)[::2], "not contiguous"),
    ([1.0, 2.0, 3.0], "list given"),
])
def test_allan_bad_arrays(bad, what):
    with pytest.raises(ValueError, match=r"^x: .*" + what):
        metro.allan(bad, 0.01)


def test_allan_nan_is_refused_as_the_cli_refuses_it():
    x = np.zeros(1000)
    x[123] = np.nan
    with pytest.raises(ValueError, match=r"x: rate sample 123 \(0-based\) is not finite") as e:
        metro.allan(x, 0.01)
    assert isinstance(e.value, metro.InputError) and e.value.kind == "input"


def test_from_arrays_bad_input():
    t = np.arange(10) * 0.01
    with pytest.raises(ValueError, match=r'columns\["gx_dps"\]: element 3 is nan'):
        bad = np.ones(10)
        bad[3] = np.nan
        metro.Session.from_arrays(t, {"gx_dps": bad})
    with pytest.raises(ValueError, match=r"^t: element 5 .* not after"):
        t2 = t.copy()
        t2[5] = t2[4]
        metro.Session.from_arrays(t2, {"gx_dps": np.ones(10)})
    with pytest.raises(ValueError, match=r'columns\["gx_dps"\]: 9 values for 10 times'):
        metro.Session.from_arrays(t, {"gx_dps": np.ones(9)})
    with pytest.raises(ValueError, match=r'columns\["GX"\]: not a column name'):
        metro.Session.from_arrays(t, {"GX": np.ones(10)})
    with pytest.raises(ValueError, match=r"^t: dtype int64"):
        metro.Session.from_arrays(np.arange(10), {"gx_dps": np.ones(10)})


def test_errors_carry_the_cli_message_and_kind(cli, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,sensor,gx_dps\n0.0,1,0.5\n0.01,1,abc\n")
    code, _, err = cli(bad, "--type-a")
    assert code == 2
    with pytest.raises(metro.InputError) as e:
        metro.load(bad)
    assert str(e.value) in err  # The CLI prints "error: file:line:column: message".
    assert (e.value.file, e.value.line, e.value.kind) == (str(bad), 3, "input")
    assert e.value.column == 3
    assert isinstance(e.value, ValueError) and isinstance(e.value, metro.Error)
    with pytest.raises(metro.InputError, match="format=nope: unknown format"):
        metro.load(bad, format="nope")
    with pytest.raises(metro.InputError, match="--taus|decade"):
        metro.type_a(STATIC, allan=True, taus="decade:0")


def test_failed_budget_is_a_failed_error():
    # An adaptive Monte Carlo asked for 6 significant digits within 10^5 trials cannot settle:
    # the run failed on valid input (the CLI's exit 1).
    budget = json.loads((BUDGETS / "jcgm101_9_2_2_additive.json").read_text())
    budget["monte_carlo"].update({"adaptive": True, "max_trials": 100000, "ndig": 6})
    with pytest.raises(metro.FailedError) as e:
        metro.budget(budget)
    assert e.value.kind == "failed" and isinstance(e.value, RuntimeError)


# --- Threads, the GIL, Ctrl-C -----------------------------------------------------------------

def test_long_calls_release_the_gil():
    x = np.random.default_rng(3).normal(size=1_000_000)
    ticks = 0
    running = True

    def count():
        nonlocal ticks
        while running:
            ticks += 1

    counter = threading.Thread(target=count)
    counter.start()
    try:
        time.sleep(0.05)
        start = ticks
        t0 = time.perf_counter()
        metro.allan(x, 0.01, taus="all", threads=1)
        elapsed = time.perf_counter() - t0
        during = ticks - start
    finally:
        running = False
        counter.join()
    assert elapsed > 0.05
    # Holding the GIL, the counting thread would not run at all during the call.
    assert during > 1000, (during, elapsed)


def test_two_threads_give_the_serial_results():
    rng = np.random.default_rng(4)
    xs = [rng.normal(size=300_000) for _ in range(2)]
    serial = [metro.allan(x, 0.005).to_json() for x in xs]
    results = [None, None]

    def run(i):
        results[i] = metro.allan(xs[i], 0.005).to_json()

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == serial


def seconds_to_stop_after_ctrl_c(call, delay_s):
    """Sends SIGINT to this process delay_s into call(); returns the seconds from the signal to
    the KeyboardInterrupt (pytest.raises fails the test if the call ends without one)."""
    sent = []

    def interrupt():
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(delay_s, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        call()
    stopped = time.perf_counter()
    timer.join()
    assert sent
    return stopped - sent[0]


main_thread_only = pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                                      reason="signals reach the main thread only")


@main_thread_only
def test_ctrl_c_interrupts_within_a_second():
    # Every m up to 250000 on 1e6 samples: minutes of work uninterrupted.
    x = np.random.default_rng(5).normal(size=1_000_000)
    assert seconds_to_stop_after_ctrl_c(lambda: metro.allan(x, 0.01, taus="every"), 0.5) < 1.0
    # The module still works after an interrupted call.
    assert metro.allan(x[:10_000].copy(), 0.01).adev.size > 0


@main_thread_only
def test_ctrl_c_interrupts_a_monte_carlo_run():
    # 2e7 fixed trials of JCGM 101 9.5: several seconds uninterrupted (12 s for 3e7 at load 8).
    budget = json.loads((BUDGETS / "jcgm101_9_5_gauge_block.json").read_text())
    budget["monte_carlo"] = {"trials": 20_000_000, "seed": 1, "adaptive": False}
    assert seconds_to_stop_after_ctrl_c(lambda: metro.budget(budget), 0.3) < 1.0

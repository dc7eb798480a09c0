# metro.calibrate, metro.blob and metro.registry against the calibrate program on the bundled
# calibration session and the golden blob.
import json
import subprocess

import pytest

import metro
from conftest import BINARY_DIR, DATASETS

CALIBRATE = BINARY_DIR / "apps" / "calibrate" / "calibrate"
SESSION = DATASETS / "calibration_session.csv"
GOLDEN = DATASETS / "golden"
DEVICE = "9ABCDEF012345678"


def calibrate(*args, cwd):
    if not CALIBRATE.exists():
        pytest.fail(f"{CALIBRATE} is not built")
    done = subprocess.run([str(CALIBRATE), *map(str, args)], capture_output=True, cwd=cwd)
    assert done.returncode == 0, done.stderr.decode()
    return done.stdout


@pytest.fixture(scope="module")
def line(tmp_path_factory):
    """calibrate fit + blob with a registry, as docs/cli.md's worked example."""
    d = tmp_path_factory.mktemp("line")
    calibrate("fit", SESSION, "-o", "calibration.json", "--registry", "line.sqlite", cwd=d)
    calibrate("blob", "calibration.json", "--sensor", "2", "--device-id", DEVICE, "-o", "tag.bin",
              "--registry", "line.sqlite", cwd=d)
    return d


def without_date(d):
    d = dict(d)
    d.pop("date_utc")
    return d


def test_fit_equals_cli(line):
    fitted = metro.calibrate.fit(SESSION)
    expected = json.loads((line / "calibration.json").read_text())
    # The fit's date is the time it ran; every other byte is the program's.
    assert without_date(fitted.to_dict()) == without_date(expected)
    assert fitted.sensors == [t["sensor"] for t in expected["tags"]]


def test_apply_equals_cli(line, tmp_path):
    calibrate("apply", line / "calibration.json", SESSION, "-o", tmp_path / "applied.csv", cwd=tmp_path)
    applied = metro.calibrate.apply(metro.load(SESSION), line / "calibration.json")
    assert applied.to_csv() == (tmp_path / "applied.csv").read_text()


def test_blob_equals_cli_and_golden(line):
    built = metro.blob.build(line / "calibration.json", sensor=2, device_id=DEVICE)
    assert built == (line / "tag.bin").read_bytes()
    # What the CLI prints as a warning is a RuntimeWarning here.
    with pytest.warns(RuntimeWarning, match="records no static_pose_temperature"):
        golden = metro.blob.build(GOLDEN / "calibration_sensor2.json", sensor=2,
                                  device_id=int(DEVICE, 16), seq=3)
    assert golden == (GOLDEN / "tag_sensor2.bin").read_bytes()


def test_inspect_equals_cli(line):
    expected = json.loads(calibrate("inspect", line / "tag.bin", "--json", cwd=line))
    assert metro.blob.inspect(line / "tag.bin") == expected
    from_bytes = metro.blob.inspect((line / "tag.bin").read_bytes(), device_id=DEVICE)
    assert from_bytes["slots"][0]["code_name"] == "METRO_FW_OK"
    broken = bytearray((line / "tag.bin").read_bytes())
    broken[100] ^= 0xFF
    assert metro.blob.inspect(bytes(broken))["slots"][0]["code_name"] == "METRO_FW_E_CRC"


def test_registry_history_equals_cli(line):
    expected = json.loads(calibrate("registry", "history", "--device-id", DEVICE, "--registry",
                                    "line.sqlite", "--json", cwd=line))
    reg = metro.registry.open(str(line / "line.sqlite"))
    history = reg.history(DEVICE)
    assert history == expected and len(history["calibrations"]) >= 1
    reg.close()
    assert reg.closed
    with pytest.raises(metro.ClosedError, match="is closed"):
        reg.history(DEVICE)
    assert history == expected  # What it returned does not depend on the registry.
    with metro.registry.open(str(line / "line.sqlite")) as again:
        assert again.history(int(DEVICE, 16)) == expected


def test_calibration_errors(tmp_path):
    with pytest.raises(metro.InputError) as e:
        metro.calibrate.fit(DATASETS / "static_imu_100hz.csv")
    assert e.value.kind == "input"
    with pytest.raises(metro.InputError, match="device"):
        metro.blob.build(GOLDEN / "calibration_sensor2.json", sensor=2, device_id="not-hex")


# --- calibrate fit's options (issue #43): each keyword equals its flag -------------------------


def segments_file(path):
    """The annotated segments of the bundled session from its simulation's timeline
    (src/sim/calibration_session.cpp: pose 0 still 2 x dwell, then per pose a move, a dwell,
    the table run and a still stop; calibration_session.csv.truth.json), 0.3 s inside each."""
    truth = json.loads((DATASETS / "calibration_session.csv.truth.json").read_text())
    dwell, move, run = truth["dwell_s"], truth["move_s"], truth["table_run_s"]
    rate = truth["table_rates_dps"][0]
    rows, t = ["kind,start_s,end_s,table_rate_dps"], 0.0
    for pose in range(truth["poses"]):
        if pose > 0:
            t += move
        still = 2 * dwell if pose == 0 else dwell
        rows.append(f"static,{t + 0.3:.2f},{t + still - 0.3:.2f},")
        t += still
        rows.append(f"table,{t + 0.3:.2f},{t + run - 0.3:.2f},{rate}")
        t += run
        rows.append(f"static,{t + 0.3:.2f},{t + dwell - 0.3:.2f},")
        t += dwell
    assert round(t * truth["rate_hz"]) == truth["rows"]  # The timeline covers the record.
    path.write_text("\n".join(rows) + "\n")
    return path


def tags_file(path):
    path.write_text(json.dumps({"2": {"name": "Sternum", "device_id": DEVICE, "profile": "generic"}}))
    return path


# (flags of `calibrate fit`, keywords of metro.calibrate.fit); {dir} is the test's directory.
FIT_OPTIONS = [
    (["--accel-model", "scale"], {"accel_model": "scale"}),
    (["--model", "scale", "--gyro-model", "bias"], {"model": "scale", "gyro_model": "bias"}),
    (["--gyro-model", "auto", "--model", "full"], {"gyro_model": "auto", "model": "full"}),
    (["--loss", "huber", "--loss-scale", "2", "--model", "full"],
     {"loss": "huber", "loss_scale": 2.0, "model": "full"}),
    (["--accel-only"], {"accel_only": True}),
    (["--min-static-s", "2"], {"min_static_s": 2.0}),
    (["--segments", "{dir}/segments.csv"], {"segments": "{dir}/segments.csv"}),
    (["--tags", "{dir}/tags.json"], {"tags": "{dir}/tags.json"}),
]


@pytest.fixture(scope="module")
def default_fit():
    return without_date(metro.calibrate.fit(SESSION).to_dict())


@pytest.mark.parametrize("flags,keywords", FIT_OPTIONS, ids=[" ".join(f) for f, _ in FIT_OPTIONS])
def test_fit_options_equal_cli(flags, keywords, tmp_path, default_fit):
    segments_file(tmp_path / "segments.csv")
    tags_file(tmp_path / "tags.json")
    flags = [f.format(dir=tmp_path) for f in flags]
    keywords = {k: v.format(dir=tmp_path) if isinstance(v, str) else v for k, v in keywords.items()}
    calibrate("fit", SESSION, "-o", "calibration.json", *flags, cwd=tmp_path)
    expected = json.loads((tmp_path / "calibration.json").read_text())
    fitted = metro.calibrate.fit(SESSION, **keywords)
    assert without_date(fitted.to_dict()) == without_date(expected)
    assert without_date(fitted.to_dict()) != default_fit  # The option changes the fit.


def test_fit_gyro_bias_at_rest_equals_cli(tmp_path):
    # --accel-model none --gyro-model bias: the gyroscope's bias at rest from one static record.
    record = DATASETS / "static_imu_100hz.csv"
    calibrate("fit", record, "-o", "calibration.json", "--accel-model", "none", "--gyro-model",
              "bias", cwd=tmp_path)
    expected = json.loads((tmp_path / "calibration.json").read_text())
    fitted = metro.calibrate.fit(record, accel_model="none", gyro_model="bias")
    assert without_date(fitted.to_dict()) == without_date(expected)
    assert all("accel" not in t and "gyro" in t for t in expected["tags"])


@pytest.mark.parametrize("keywords,match", [
    ({"model": "diagonal"}, "model=diagonal: expected auto, bias, scale or full"),
    ({"accel_model": "affine"}, "accel_model=affine: expected auto, bias, scale, full or none"),
    ({"gyro_model": "none"}, "gyro_model=none: expected auto, bias, scale or full"),
    ({"loss": "l1"}, "loss=l1: expected none, huber or cauchy"),
    ({"loss_scale": 0.0}, "loss_scale must be > 0"),
    ({"min_static_s": -1.0}, "min_static_s must be > 0"),
    ({"accel_model": "none"}, "--gyro-model bias"),
    ({"accel_model": "none", "gyro_model": "bias", "accel_only": True}, "nothing to calibrate"),
    ({"segments": "missing_segments.csv"}, "missing_segments.csv"),
    ({"tags": "missing_tags.json"}, "missing_tags.json"),
])
def test_fit_bad_option_is_value_error(keywords, match):
    with pytest.raises(ValueError, match=match) as e:
        metro.calibrate.fit(SESSION, **keywords)
    assert isinstance(e.value, metro.InputError)


def test_fit_imutk_pair_equals_cli(tmp_path):
    xsens = DATASETS / "external" / "imu_tk_xsens"
    acc, gyro = xsens / "xsens_acc.mat", xsens / "xsens_gyro.mat"
    calibrate("fit", "--imutk", acc, gyro, "-o", "calibration.json", cwd=tmp_path)
    expected = json.loads((tmp_path / "calibration.json").read_text())
    assert without_date(metro.calibrate.fit([(acc, gyro)]).to_dict()) == without_date(expected)
    assert without_date(metro.calibrate.fit((acc, gyro)).to_dict()) == without_date(expected)
    with pytest.raises(ValueError, match="imu_tk input is \\(ACC, GYRO\\), two files"):
        metro.calibrate.fit([(acc, gyro, acc)])


# --- registry drift, due and export against `calibrate registry` --------------------------------


@pytest.fixture(scope="module")
def recalibrated(tmp_path_factory):
    """A registry with two calibrations of one device (the second with --model full), each
    written to it as a blob; their shared input record makes drift warn."""
    d = tmp_path_factory.mktemp("recalibrated")
    for n, model in [(1, "auto"), (2, "full")]:
        calibrate("fit", SESSION, "-o", f"cal{n}.json", "--model", model, "--registry", "reg.sqlite",
                  "--station", "bench, \"A\"", cwd=d)
        calibrate("blob", f"cal{n}.json", "--sensor", "2", "--device-id", DEVICE, "--seq", n, "-o",
                  f"tag{n}.bin", "--registry", "reg.sqlite", cwd=d)
    return d


def registry_cli(d, *args):
    return calibrate("registry", *args, "--registry", "reg.sqlite", cwd=d)


def test_registry_drift_equals_cli(recalibrated):
    expected = json.loads(registry_cli(recalibrated, "drift", "--device-id", DEVICE, "--json"))
    with metro.registry.open(str(recalibrated / "reg.sqlite")) as reg:
        with pytest.warns(RuntimeWarning, match="share an input record"):
            drift = reg.drift(DEVICE)
    assert drift == expected and len(drift["constants"]) > 0
    with pytest.raises(metro.InputError, match="device"):
        metro.registry.open(str(recalibrated / "reg.sqlite")).drift("not-hex")


def test_registry_due_equals_cli(recalibrated):
    reg = metro.registry.open(str(recalibrated / "reg.sqlite"))
    for at, days, all_ in [("2030-01-01T00:00:00Z", 30, False), ("2000-01-01T00:00:00Z", 365, True),
                           ("2000-01-01T00:00:00Z", 365, False)]:
        flags = ["--at", at, "--interval-days", str(days)] + (["--all"] if all_ else [])
        expected = json.loads(registry_cli(recalibrated, "due", *flags, "--json"))
        assert reg.due(days, at_utc=at, all=all_) == expected
    # Judged now, the fits of today are not due within the default year (365 days).
    now = reg.due()
    assert now["interval_days"] == 365 and now["devices"] == []
    assert len(reg.due(30, at_utc="2030-01-01T00:00:00Z")["devices"]) == 1
    with pytest.raises(ValueError, match="interval_days=0.0: expected a number > 0"):
        reg.due(0)
    with pytest.raises(ValueError, match="at_utc='yesterday': expected ISO 8601 UTC"):
        reg.due(at_utc="yesterday")


def test_registry_export_equals_cli(recalibrated):
    reg = metro.registry.open(str(recalibrated / "reg.sqlite"))
    csv = reg.export()
    assert csv == registry_cli(recalibrated, "export").decode()
    assert '"bench, ""A"""' in csv  # A station with a comma and quotes, quoted as CSV.
    expected = json.loads(registry_cli(recalibrated, "export", "--format", "json"))
    exported = reg.export(format="json")
    assert exported == expected and len(exported["calibrations"]) == 2
    with pytest.raises(ValueError, match="format=xml: expected csv or json"):
        reg.export(format="xml")


def test_registry_closed(recalibrated):
    reg = metro.registry.open(str(recalibrated / "reg.sqlite"))
    reg.close()
    for call in [lambda: reg.drift(DEVICE), lambda: reg.due(), lambda: reg.export(),
                 lambda: reg.export(format="json")]:
        with pytest.raises(metro.ClosedError, match="is closed"):
            call()

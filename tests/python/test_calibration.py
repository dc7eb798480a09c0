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

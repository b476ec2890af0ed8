"""``dualarm-qp drive --cell mujoco`` stopped by SIGINT or SIGTERM in the middle of the
path: exit code 130, a whole record that says why, and the arms brought to rest within
their limits (checked from the record's sent columns and recorded joints)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from record_checks import check_motion, check_sent, read_record, sent_names
from sigint import child_default_sigint

pytest.importorskip("mujoco")
pytest.importorskip("franky_sim")  # the FR3's description

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "fr3_pair.yaml"


@pytest.mark.slow
@pytest.mark.sigint
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_drive_and_the_record_is_whole(tmp_path: Path, sig: int) -> None:
    # the simulation no faster than the wall clock (cell.realtime): the signal comes in
    # the middle of the path however fast the machine
    data = yaml.safe_load(CONFIG.read_text())
    data["cell"]["realtime"] = True
    config = tmp_path / "fr3_pair_realtime.yaml"
    config.write_text(yaml.safe_dump(data))
    out = tmp_path / "drive"
    proc = subprocess.Popen([sys.executable, "-m", "dualarm_qp.cli", "drive", str(config),
                             "--cell", "mujoco", "--out", str(out), "--no-plots"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=child_default_sigint)
    try:
        deadline = time.monotonic() + 120
        while not out.exists():  # made just before the cell is opened
            assert proc.poll() is None and time.monotonic() < deadline, proc.stderr
            time.sleep(0.01)
        time.sleep(1.5)  # the cell is opened before the folder is made: 1.5 s of 3.4
        assert proc.poll() is None, "the drive ended before the signal"
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "interrupted" in stderr, stderr
    rec = read_record(out)
    s = rec.summary
    name = signal.Signals(sig).name
    assert s["status"] == "interrupted" and name in s["message"], s["message"]
    assert s["failure"]["criterion"] == "interrupted"
    assert 0 < s["path_completed_pct"] < 100
    print(f"{name} at {s['path_completed_pct']:.0f}% of the path, {s['wall_time_s']:.1f} s")
    stop = s["cell"]["stop"]
    assert stop["reason"] == "interrupted" and stop["at_rest"] and stop["samples"] > 1
    assert stop["acceleration_ratio_max"] <= 1 + 1e-9 and stop["jerk_ratio_max"] <= 1 + 1e-9
    assert np.any(rec.cols(sent_names(), rec.control)[-1])  # moving when it was stopped
    check_sent(rec, CONFIG)  # the stop's commands within the limits, the last at rest
    check_motion(rec, CONFIG)  # and the joints' recorded motion, the stop's rows too
    # the simulated grasp (what a simulator measures) stayed on the estimate's
    measured = rec.col("grasp_measured", rec.control)
    assert np.max(np.abs(measured - rec.col("grasp", rec.control))) < 1e-3

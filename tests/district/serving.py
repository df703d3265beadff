"""Start `twin district serve` on a district file and wait until a house serves its devices."""
import subprocess
import sys
import time
from pathlib import Path


def serve(tmp_path: Path, district_text: str, days: float, speed: float, house: str = "house1"):
    """(the running `twin district serve` process, its output folder), once `house` is serving."""
    district = tmp_path / "district.toml"
    district.write_text(district_text)
    out = tmp_path / "run"
    twin = subprocess.Popen([sys.executable, "-m", "cli.main", "district", "serve", str(district),
                             "--days", str(days), "--speed", str(speed), "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    log = out / "logs" / f"{house}.log"
    deadline = time.monotonic() + 120
    while not (log.exists() and "serving modbus-tcp" in log.read_text()):
        assert twin.poll() is None, twin.communicate()
        assert time.monotonic() < deadline, f"{house} did not start serving within 120 s"
        time.sleep(0.1)
    return twin, out

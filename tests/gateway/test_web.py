"""Live view: the JSON API against a running lock-step gateway (values, token enforcement), the
`twin serve --http` command line, and the page in a real headless browser (values shown in the
schematic and the device tables equal the plant's at that moment)."""
import importlib.util
import json
import re
import shutil
import subprocess
import sys
import time
import urllib.error
import urllib.request

import pytest
from pymodbus.client import ModbusTcpClient

from gateway.clock import LockStepClock
from gateway.maps import codec
from gateway.runtime import Runtime
from gateway.web.server import LiveServer
from plant.house import load_house
from tests.conftest import require_tool

BOILER = 2  # unit id of boiler_wolf_cgb
TOKEN = "test-token-5f2a"


@pytest.fixture
def gateway():
    """A lock-step runtime with Modbus TCP and the live view (token set), its boiler driven by a
    Modbus client at 10 V, stepped 200 s (the watchdog, 300 s, stays armed)."""
    rt = Runtime(load_house("house1", controller="external"), clock=LockStepClock(1.0))
    tcp = rt.add("modbus-tcp", host="127.0.0.1", port=0)
    rt.start()
    web = LiveServer(rt, "127.0.0.1", 0, token=TOKEN)
    web.start()
    client = ModbusTcpClient("127.0.0.1", port=tcp.port, timeout=2)
    client.connect()
    assert not client.write_register(200, 1000, device_id=BOILER).isError()  # 10.00 V demand
    assert client.write_register(200, 1500, device_id=BOILER).isError()      # 15 V: refused
    rt.clock.step(200)
    yield rt, web, client
    client.close()
    web.stop()
    rt.stop()


def get(web, path):
    with urllib.request.urlopen(web.url + path.lstrip("/"), timeout=5) as r:
        return json.load(r)


def post(web, path, body, token=None):
    headers = {"Content-Type": "application/json"}
    if token is not None:
        headers["Authorization"] = f"Bearer {token}"
    req = urllib.request.Request(web.url + path.lstrip("/"), data=json.dumps(body).encode(),
                                 headers=headers, method="POST")
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.load(r)
    except urllib.error.HTTPError as exc:
        return exc.code, json.load(exc)


def served(point, si):
    """(raw, engineering value) a device serves for plant value `si`, through the one codec."""
    raw = codec.to_raw(point, codec.to_device(point, si))
    return raw, codec.from_raw(point, raw)


def test_signals_equal_the_plant(gateway):
    rt, web, _ = gateway
    data = get(web, "/api/signals")
    assert data["t"] == rt.house.t == 200.0
    assert list(data["values"]) == rt.house.catalogue.names
    for name, value in data["values"].items():
        assert value == rt.house.get(name), name  # JSON carries doubles exactly
    assert data["units"]["storage.T_sensor_5"] == "degC"
    assert data["states"]["boiler.mode"]["3"] == "steady"
    one = get(web, "/api/signals?names=boiler.T_sup,zone.T_room")
    assert one["values"] == {"boiler.T_sup": rt.house.get("boiler.T_sup"),
                             "zone.T_room": rt.house.get("zone.T_room")}
    with pytest.raises(urllib.error.HTTPError) as err:
        get(web, "/api/signals?names=boiler.T_nope")
    assert err.value.code == 404


def test_devices_clients_clock_and_history(gateway):
    rt, web, client = gateway
    boiler = next(d for d in get(web, "/api/devices")["devices"] if d["id"] == "boiler_wolf_cgb")
    dev = rt.devices["boiler_wolf_cgb"]
    points = {p["name"]: p for p in boiler["points"]}
    raw, value = served(dev.map.point("t_boiler"), rt.house.get("boiler.T_sup"))
    assert points["t_boiler"]["raw"] == raw and points["t_boiler"]["value"] == pytest.approx(value, abs=1e-9)
    assert points["demand_voltage"]["raw"] == 1000 and points["demand_voltage"]["value"] == pytest.approx(10.0)
    assert boiler["remote"] and boiler["watchdog"]["state"] == "armed"
    assert boiler["watchdog"]["remaining_s"] == pytest.approx(dev.watchdog.timeout_s - 200)

    clients = get(web, "/api/clients")
    local = f"127.0.0.1:{client.socket.getsockname()[1]}"
    assert clients["connections"]["modbus-tcp"] == [local]
    audit = clients["clients"][f"modbus-tcp:{local}"]
    assert audit["writes_accepted"] == 1 and sum(audit["writes_refused"].values()) == 1
    assert clients["watchdogs"]["boiler_wolf_cgb"] == "armed"
    assert [e["accepted"] for e in clients["events"] if e["kind"] == "write"] == [False, True]

    clock = get(web, "/api/clock")
    assert clock["mode"] == "lock-step" and clock["t"] == 200.0 and clock["steps"] == 200
    assert clock["house"] == "house1" and clock["start"] == str(rt.house.start)

    t0 = rt.house.t
    deadline = time.monotonic() + 5
    while not get(web, "/api/history?names=zone.T_room")["t"] or \
            get(web, "/api/history?names=zone.T_room")["t"][-1] != t0:
        assert time.monotonic() < deadline, "history never sampled the current time"
        time.sleep(0.05)
    rt.clock.step(10)
    while get(web, "/api/history?names=zone.T_room")["t"][-1] != t0 + 10:
        assert time.monotonic() < deadline + 5, "history did not follow the plant"
        time.sleep(0.05)
    h = get(web, "/api/history?names=zone.T_room,boiler.T_sup")
    assert h["series"]["boiler.T_sup"][-1] == rt.house.get("boiler.T_sup")
    assert h["t"] == sorted(h["t"])


def test_fault_injection_needs_the_token(gateway):
    rt, web, client = gateway
    dev = rt.devices["boiler_wolf_cgb"]
    trip = {"device": "boiler_wolf_cgb", "kind": "trip"}
    for token in (None, "wrong", "", TOKEN + "x"):
        status, body = post(web, "/api/faults", trip, token)
        assert status == 403 and "token" in body["error"]
    assert not dev.faults.tripped and dev.fault_code() == 0
    assert not any(e["kind"] == "fault" for e in get(web, "/api/clients")["events"])

    status, body = post(web, "/api/faults", trip, TOKEN)
    assert status == 200 and body["applied"]["kind"] == "trip" and body["t"] == rt.house.t
    assert dev.faults.tripped and dev.fault_code() == 4
    assert client.read_input_registers(1, count=1, device_id=BOILER).registers == [4]  # on the bus
    assert rt.house.get("boiler.U_set") == 0.0  # the map's trip_forces
    boiler = next(d for d in get(web, "/api/devices")["devices"] if d["id"] == "boiler_wolf_cgb")
    assert boiler["tripped"] and boiler["fault_code"] == 4
    status, _ = post(web, "/api/faults", {"device": "storage_io", "kind": "sensor_drift",
                                          "point": "t_sensor_5", "delta": 2.5}, TOKEN)
    if status == 400:  # the point name differs in this map: take its first signal point
        point = next(p.name for p in rt.devices["storage_io"].map.points if p.signal)
        status, _ = post(web, "/api/faults", {"device": "storage_io", "kind": "sensor_drift",
                                              "point": point, "delta": 2.5}, TOKEN)
    assert status == 200 and rt.devices["storage_io"].faults.sensors
    status, body = post(web, "/api/faults", {"device": "nope", "kind": "trip"}, TOKEN)
    assert status == 400 and "boiler_wolf_cgb" in body["error"]  # names the valid devices


def test_fault_injection_is_off_without_a_token(gateway):
    rt, _, _ = gateway
    web = LiveServer(rt, "127.0.0.1", 0)
    web.start()
    try:
        assert get(web, "/api/faults")["enabled"] is False
        for token in (None, "", TOKEN):
            status, body = post(web, "/api/faults", {"device": "boiler_wolf_cgb", "kind": "trip"}, token)
            assert status == 403 and "--http-token" in body["error"]
        assert not rt.devices["boiler_wolf_cgb"].faults.tripped
    finally:
        web.stop()


def test_twin_serve_http_serves_the_api(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "cli.main", "serve", "house1", "--modbus-tcp", "127.0.0.1:0",
         "--lock-step", "--http", "127.0.0.1:0"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        url = None
        for _ in range(20):
            line = proc.stdout.readline()
            m = re.match(r"live view: (http://\S+) \(fault injection over HTTP off\)", line)
            if m:
                url = m.group(1)
                break
        assert url, "twin serve did not print the live view address"
        proc.stdin.write("step 5\n")
        proc.stdin.flush()
        for _ in range(20):
            if proc.stdout.readline().startswith("t="):
                break
        else:
            pytest.fail("twin serve did not answer 'step 5'")
        with urllib.request.urlopen(url + "api/clock", timeout=5) as r:
            assert json.load(r)["t"] == 5.0
        with urllib.request.urlopen(url, timeout=5) as r:
            assert b'id="schematic"' in r.read()
        proc.stdin.write("quit\n")
        proc.stdin.flush()
        assert proc.wait(20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()


# ---------------------------------------------------------------------------- the browser
def _browser():
    require_tool("chromium", "apt-get install chromium")
    require_tool("chromedriver", "apt-get install chromium-driver")
    require_tool("selenium", 'pip install -e ".[test]"', found=importlib.util.find_spec("selenium") is not None)
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1400,900"):
        opts.add_argument(arg)
    # the driver comes from the Debian package: Selenium Manager must not try to download one
    return webdriver.Chrome(service=Service(executable_path=shutil.which("chromedriver")), options=opts)


def _shown(el) -> float:
    """The number displayed in an element ('61.3 °C' -> 61.3)."""
    m = re.search(r"-?\d+(?:\.\d+)?", el.text)
    assert m, f"no number shown in {el.get_attribute('outerHTML')}"
    return float(m.group())


def _wait_for_time(driver, t, timeout=15.0):
    deadline = time.monotonic() + timeout
    while driver.execute_script("return document.body.dataset.t") != f"{t:g}":
        assert time.monotonic() < deadline, f"page never showed t = {t:g} s"
        time.sleep(0.1)


def _check_page(driver, rt):
    from selenium.webdriver.common.by import By

    house = rt.house
    for tank in ("storage", "dhw_storage"):
        for k in range(1, 11):
            name = f"{tank}.T_sensor_{k}"
            el = driver.find_element(By.CSS_SELECTOR, f'#{tank} [data-signal="{name}"]')
            assert abs(_shown(el) - house.get(name)) <= 0.05 + 1e-9, (name, el.text, house.get(name))
    for box, name, digits in (("chp-box", "chp.T_sup", 1), ("boiler-box", "boiler.T_sup", 1),
                              ("boiler-box", "boiler.Q_flow", 2)):
        el = driver.find_element(By.CSS_SELECTOR, f'#{box} [data-signal="{name}"]')
        scale = 1e-3 if name.endswith("Q_flow") else 1.0
        assert abs(_shown(el) - house.get(name) * scale) <= 0.5 * 10 ** -digits + 1e-9, (name, el.text)
    for family in ("chp", "boiler"):  # state names as the catalogue describes the codes
        sig = house.catalogue.signal(f"{family}.mode")
        names = dict(re.findall(r"(\d+) ([a-z][a-z -]*?)\s*(?:,|$)", sig.description))
        expected = names[str(int(round(house.get(f"{family}.mode"))))]
        assert driver.find_element(By.ID, f"{family}-state").text == expected
    dev = rt.devices["boiler_wolf_cgb"]
    raw, value = served(dev.map.point("t_boiler"), house.get("boiler.T_sup"))
    row = driver.find_element(By.ID, "pt-boiler_wolf_cgb-t_boiler")
    assert row.find_element(By.CLASS_NAME, "raw").text == str(raw)
    assert float(row.find_element(By.CLASS_NAME, "value").text) == pytest.approx(value, abs=1e-9)
    chp = rt.devices["chp_neotower2"].map.point("unit_mode")
    mode = int(round(house.get("chp.mode")))
    cell = driver.find_element(By.ID, "pt-chp_neotower2-unit_mode").find_element(By.CLASS_NAME, "value")
    assert cell.text == f"{mode} {dict(chp.enum)[mode]}"


def test_page_shows_the_plant_live(gateway):
    from selenium.webdriver.common.by import By

    rt, web, _ = gateway
    driver = _browser()
    try:
        driver.get(web.url)
        _wait_for_time(driver, rt.house.t)
        assert rt.house.get("boiler.mode") != 0  # driven at 10 V: the schematic shows it running
        assert "running" in driver.find_element(By.ID, "boiler-box").get_attribute("class")
        _check_page(driver, rt)
        rt.clock.step(60)  # the page follows without a reload
        _wait_for_time(driver, rt.house.t)
        _check_page(driver, rt)
        assert "armed" in driver.find_element(By.ID, "watchdogs").text
        assert driver.find_elements(By.CSS_SELECTOR, "#plot canvas"), "no rolling plot drawn"
        resources = driver.execute_script(
            "return performance.getEntriesByType('resource').map(e => e.name)")
        assert resources and all(r.startswith(web.url) for r in resources), resources
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
    finally:
        driver.quit()

"""train.sh and make_data.sh build the commands they should: run with a stand-in Python and a
stand-in omnimvs binary that record their arguments."""
import os
import shutil
import stat
import subprocess

import pytest

PICK = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(os.path.dirname(PICK))
TEN = ("things-s201 things-s208 things-s211 house-s202 house-s210 house-s213 things-hard-s203 "
       "things-hard-s209 things-hard-s212 house-hard-s207").split()

pytestmark = pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")


def stand_in(path, body):
    path.write_text("#!/usr/bin/env bash\n" + body)
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return str(path)


def run(script, env, *args):
    full = {k: v for k, v in os.environ.items() if not k.startswith("PICK_")}
    full.update(env)
    return subprocess.run(["bash", os.path.join(PICK, script), *args], env=full,
                          capture_output=True, text=True)


@pytest.fixture
def recorder(tmp_path):
    log = tmp_path / "calls.log"
    py = stand_in(tmp_path / "py", f'echo "PY $* | init=${{PICK_INIT:-}} lr=${{PICK_LR:-}} sky=${{SKY_WEIGHT:-}}" >> {log}\n'
                  # pick_inputs.py / second_inputs.py: write the last argument (the output file)
                  'case $1 in *_inputs.py) touch "${@: -1}" ;; esac\n')
    return py, log


def test_train_needs_data_and_out(tmp_path):
    r = run("train.sh", {})
    assert r.returncode == 2 and "set DATA" in r.stderr
    r = run("train.sh", {"DATA": str(tmp_path), "OUT": str(tmp_path / "p.safetensors")})
    assert r.returncode == 2 and "must end in .pt" in r.stderr
    r = run("train.sh", {"DATA": str(tmp_path), "OUT": str(tmp_path / "p.pt")})
    assert r.returncode == 1 and "f-things-s201.npz" in r.stderr


def test_train_builds_pick_6s_command(tmp_path, recorder):
    py, log = recorder
    data = tmp_path / "data"
    data.mkdir()
    for s in TEN:
        (data / f"f-{s}.npz").touch()
    for s in ("things", "house", "hhouse"):
        (data / f"v-{s}.npz").touch()
    (data / "pick5.pt").touch()
    r = run("train.sh", {"DATA": str(data), "OUT": str(data / "pick6.pt"), "STEPS": "3000",
                         "LR": "3e-4", "INIT": str(data / "pick5.pt"), "PY": py})
    assert r.returncode == 0, r.stderr
    args, env = log.read_text().strip().split(" | ")
    words = args.split()
    assert words[1] == os.path.join(PICK, "train_pick.py") and words[2] == "3000"
    assert words[3].split(",") == [str(data / f"f-{s}.npz") for s in TEN]
    assert words[4].split(",") == [str(data / f"v-{s}.npz") for s in ("things", "house", "hhouse")]
    assert words[5:] == ["16", str(data / "pick6.pt"), "2"]
    assert env == f"init={data / 'pick5.pt'} lr=3e-4 sky=0.25"


def test_train_flags_and_second_pick_prefix(tmp_path, recorder):
    py, log = recorder
    data = tmp_path / "data"
    data.mkdir()
    for s in ("things-s201", "house-s202"):
        (data / f"s-{s}.npz").touch()
    for s in ("things", "house", "hhouse"):
        (data / f"sv-{s}.npz").touch()
    r = run("train.sh", {"PY": py}, "--data", str(data), "--out", str(data / "x.pt"), "--prefix", "s",
            "--sets", "house-s202 things-s201", "--width", "8", "--steps", "10", "--threads", "1")
    assert r.returncode == 0, r.stderr
    args, env = log.read_text().strip().split(" | ")
    words = args.split()
    assert words[2] == "10"
    assert words[3] == f"{data}/s-house-s202.npz,{data}/s-things-s201.npz"
    assert words[4].startswith(f"{data}/sv-things.npz,")
    assert words[5:] == ["8", str(data / "x.pt"), "1"]
    assert env == "init= lr=1e-3 sky=0.25"


def test_make_data_first_and_second(tmp_path, recorder):
    py, log = recorder
    calls = tmp_path / "omnimvs.log"
    # The stand-in binary: records its arguments, makes the folder given to --out.
    omnimvs = stand_in(tmp_path / "omnimvs", f'echo "$*" >> {calls}\n'
                       'while [ $# -gt 0 ]; do [ "$1" = --out ] && mkdir -p "$2"; shift; done\n')
    data = tmp_path / "data"
    env = {"DATA": str(data), "OMNIMVS": omnimvs, "PY": py, "JOBS": "2"}
    r = run("make_data.sh", env, "first", "house-s202")
    assert r.returncode == 0, r.stderr
    binary = calls.read_text().splitlines()
    assert f"synth --kind house --difficulty standard --frames 1..100 --seed 202 --out {data}/house-s202" in binary
    assert f"infer --pick off --frames 1..100 --out {data}/out-house-s202 {data}/house-s202" in binary
    assert f"synth --kind house --difficulty hard --frames 481..500 --seed 107 --out {data}/house-hard-s107" in binary
    assert f"infer --pick off --frames 481..500 --out {data}/out-val-things-s101 {data}/things-s101" in binary
    assert len(binary) == 8  # three validation sets and one training set, two commands each
    python = log.read_text()
    assert f"pick_inputs.py {data}/house-s202 {data}/out-house-s202 1 100 {data}/f-house-s202.npz" in python
    assert f"pick_inputs.py {data}/house-hard-s107 {data}/out-val-house-hard-s107 481 500 {data}/v-hhouse.npz" in python
    for name in ("f-house-s202", "v-things", "v-house", "v-hhouse"):
        assert (data / f"{name}.npz").exists()
    # Again: everything is there, nothing runs.
    r = run("make_data.sh", env, "first", "house-s202")
    assert r.returncode == 0 and len(calls.read_text().splitlines()) == 8
    assert len(log.read_text().splitlines()) == 4
    # The second pick's data from the bundled first pick.
    r = run("make_data.sh", env, "second", "house-s202")
    assert r.returncode == 0, r.stderr
    bundled = os.path.join(ROOT, "models", "omnimvs-cascade-pick.safetensors")
    python = log.read_text()
    assert (f"second_inputs.py {data}/f-house-s202.npz {data}/house-s202 {data}/out-house-s202 1 100 "
            f"{bundled} {data}/s-house-s202.npz") in python
    assert (f"second_inputs.py {data}/v-things.npz {data}/things-s101 {data}/out-val-things-s101 481 500 "
            f"{bundled} {data}/sv-things.npz") in python


def test_make_data_refuses_unknown_sets(tmp_path):
    r = run("make_data.sh", {"DATA": str(tmp_path)}, "first", "things-s999")
    assert r.returncode == 2 and "unknown set" in r.stderr
    r = run("make_data.sh", {})
    assert r.returncode == 2

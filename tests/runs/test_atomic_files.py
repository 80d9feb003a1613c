"""pacto_ng.files: writes that are whole or absent, the folder lock, what --overwrite removes.

No optimisation here: the helpers on their own, failures made real (an exception inside the
writer, a file size limit in a subprocess, a lock holder killed with SIGKILL)."""
import errno
import json
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from pacto_ng.files import (LOCK_NAME, FolderLock, WriteError, atomic_path, atomic_write_bytes,
                            atomic_write_text, check_tail, claim_folder, cleanup_temps,
                            refuse_reuse, remove_outputs, temp_path)
from pacto_ng.params import InputError


def test_atomic_write_replaces_whole_and_leaves_no_temporary(tmp_path):
    f = tmp_path / "summary.json"
    f.write_text("old")
    atomic_write_text(f, '{"a": 1}')
    assert f.read_text() == '{"a": 1}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]
    atomic_write_bytes(tmp_path / "b.bin", b"\x00\x01")
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01"


def test_temporary_keeps_the_folder_and_suffix(tmp_path):
    t = temp_path(tmp_path / "design.vtu")
    assert t.parent == tmp_path and t.suffix == ".vtu"
    assert t.name == f"design.tmp-{os.getpid()}.vtu"


def test_a_failing_writer_leaves_the_old_file_unchanged(tmp_path):
    f = tmp_path / "design.png"
    f.write_bytes(b"old picture")
    with pytest.raises(WriteError) as info:
        with atomic_path(f) as tmp:
            tmp.write_bytes(b"half a pic")
            raise OSError(errno.ENOSPC, "No space left on device")
    msg = str(info.value)
    assert f"cannot write '{f}'" in msg and "disk is full" in msg and "\n" not in msg
    assert isinstance(info.value, InputError) and info.value.no_space
    assert f.read_bytes() == b"old picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.png"]


def test_an_interrupt_inside_the_writer_leaves_the_old_file(tmp_path):
    f = tmp_path / "history.csv"
    f.write_text("a,b\n1,2\n")
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(f) as tmp:
            tmp.write_text("a,b\n")
            raise KeyboardInterrupt
    assert f.read_text() == "a,b\n1,2\n"
    assert [p.name for p in tmp_path.iterdir()] == ["history.csv"]


def test_a_writer_that_writes_nothing_is_an_error(tmp_path):
    with pytest.raises(WriteError, match="wrote nothing"):
        with atomic_path(tmp_path / "design.vtu"):
            pass
    assert not (tmp_path / "design.vtu").exists()


def test_check_tail_catches_a_file_cut_short(tmp_path):
    f = tmp_path / "x.vtu"
    f.write_bytes(b"<VTKFile>\n<AppendedData>\x00\x01\n</AppendedData>\n</VTKFile>\n")
    check_tail(f, b"</VTKFile>", tmp_path / "design.vtu")
    f.write_bytes(b"<VTKFile>\n<AppendedData>\x00\x01")
    with pytest.raises(WriteError, match="design.vtu' .the file was cut short"):
        check_tail(f, b"</VTKFile>", tmp_path / "design.vtu")


def test_file_size_limit_keeps_the_old_file(tmp_path):
    """A real failed write: ``ulimit -f`` in a subprocess (SIGXFSZ ignored, so write() fails
    with EFBIG): the old file keeps its bytes, no temporary is left, the error is one line."""
    f = tmp_path / "checkpoint.npz"
    f.write_bytes(b"k" * 1000)
    code = textwrap.dedent(f"""
        import resource, signal, sys
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        from pacto_ng.files import atomic_write_bytes, WriteError
        try:
            atomic_write_bytes({str(f)!r}, b"n" * 100000)
        except WriteError as err:
            print(err)
            sys.exit(3)
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 3, r.stderr
    assert "cannot write" in r.stdout and "File too large" in r.stdout
    assert f.read_bytes() == b"k" * 1000
    assert [p.name for p in tmp_path.iterdir()] == ["checkpoint.npz"]


# -- the lock ----------------------------------------------------------------------------------
HOLD = """
import sys, time
from pacto_ng.files import FolderLock
FolderLock(sys.argv[1], "run").acquire()
print("locked", flush=True)
time.sleep(600)
"""


def test_a_locked_folder_is_refused_and_a_killed_holder_frees_it(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(tmp_path)], stdout=subprocess.PIPE,
                              text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(InputError) as info:
            FolderLock(tmp_path, "run").acquire()
        msg = str(info.value)
        assert "being written by another pacto process" in msg
        assert f"pid {holder.pid}" in msg and "another --out" in msg
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    with FolderLock(tmp_path, "run") as lock:  # the kernel dropped the dead holder's lock
        assert lock._fd is not None
    assert (tmp_path / LOCK_NAME).is_file()


def test_the_lock_is_released_after_use(tmp_path):
    with FolderLock(tmp_path, "run"):
        with pytest.raises(InputError):
            FolderLock(tmp_path, "evaluate").acquire()  # another descriptor: refused too
    FolderLock(tmp_path, "evaluate").acquire().release()


# -- run folders -------------------------------------------------------------------------------
def _fake_run(folder, case="pa-inverter"):
    folder.mkdir(exist_ok=True)
    (folder / "params.json").write_text(json.dumps({"case": case, "params": {}}))
    (folder / "summary.json").write_text(json.dumps({"case": case}))
    for name in ("checkpoint.npz", "history.csv", "design.vtu", "design.png", "pressure.png",
                 "convergence.png"):
        (folder / name).write_bytes(b"x")
    (folder / "analysis").mkdir()
    for name in ("analysis.json", "report.md", "design.stl"):
        (folder / "analysis" / name).write_text("a")


def test_refuse_reuse_says_what_to_do(tmp_path):
    refuse_reuse(tmp_path, "run")  # empty: fine
    (tmp_path / "notes.txt").write_text("mine")
    refuse_reuse(tmp_path, "run")  # a user's file is no run
    _fake_run(tmp_path)
    with pytest.raises(InputError) as info:
        refuse_reuse(tmp_path, "run")
    msg = str(info.value)
    assert f"'pacto resume {tmp_path}'" in msg and "another --out" in msg and "--overwrite" in msg
    with pytest.raises(InputError) as info:
        refuse_reuse(tmp_path, "evaluate")
    assert "pacto resume" not in str(info.value) and "--overwrite" in str(info.value)


def test_overwrite_removes_exactly_pactos_files(tmp_path):
    _fake_run(tmp_path)
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "design.tmp-99.vtu").write_text("left by a killed run")
    (tmp_path / "notes.tmp-3.txt").write_text("mine too")
    remove_outputs(tmp_path, "run")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.tmp-3.txt", "notes.txt"]
    assert (tmp_path / "notes.txt").read_text() == "mine"


@pytest.mark.parametrize("plant", ["foreign_params", "user_file_in_analysis", "broken_summary"])
def test_overwrite_refuses_when_unsure_and_removes_nothing(tmp_path, plant):
    _fake_run(tmp_path)
    if plant == "foreign_params":
        (tmp_path / "params.json").write_text('{"learning_rate": 0.1}')
    elif plant == "user_file_in_analysis":
        (tmp_path / "analysis" / "my_notes.md").write_text("mine")
    else:
        (tmp_path / "summary.json").write_text("<html>")
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    with pytest.raises(InputError, match="was not written by pacto: nothing removed"):
        remove_outputs(tmp_path, "run")
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_claim_folder_clears_temporaries_of_killed_writers(tmp_path):
    (tmp_path / "checkpoint.tmp-12345.npz").write_bytes(b"half")
    (tmp_path / "checkpoint.npz.tmp.npz").write_bytes(b"half, older name")
    (tmp_path / "mine.tmp-1.dat").write_bytes(b"user")
    lock = claim_folder(tmp_path, "run")
    lock.release()
    assert sorted(p.name for p in tmp_path.iterdir()) == [LOCK_NAME, "mine.tmp-1.dat"]
    assert cleanup_temps(tmp_path) == []

"""A run refused for a bad input while its problem is built leaves the file system as it found
it: no ``.pacto.lock`` it made, no output folder (or parent folder) it made; a folder that was
there stays, with what it held."""
import os

import pytest

from pacto_ng.cli import main
from pacto_ng.files import LOCK_NAME, FolderLock, claim_folder
from pacto_ng.params import InputError
from pacto_ng.template import TEMPLATE

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


def _bad_case(folder):
    """The template's finger whose set-up names a void region the geometry does not have: a
    bad input found while the problem is built (after the output folder is claimed)."""
    text = TEMPLATE.format(name="bad", file="bad.py")
    assert 'void=("chamber",),' in text
    path = folder / "bad.py"
    path.write_text(text.replace('void=("chamber",),', 'void=("no_such_chamber",),'))
    return path


def _run(case, out, capsys):
    code = main(["run", "--no-part", str(case), "--iterations", "1", "--maxh", "0.004", "--out", str(out),
                 "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "no_such_chamber" in err and err.strip().count("\n") == 0, err


def test_a_refused_run_removes_the_folders_it_made(tmp_path, capsys):
    case = _bad_case(tmp_path)
    _run(case, tmp_path / "NEW", capsys)
    assert not (tmp_path / "NEW").exists()
    # with parents that did not exist either: none of them is left
    _run(case, tmp_path / "a" / "b" / "NEW", capsys)
    assert not (tmp_path / "a").exists()
    assert sorted(os.listdir(tmp_path)) == ["bad.py"]


def test_a_refused_run_leaves_an_existing_folder_as_it_was(tmp_path, capsys):
    case = _bad_case(tmp_path)
    empty = tmp_path / "empty"
    empty.mkdir()
    _run(case, empty, capsys)
    assert empty.is_dir() and os.listdir(empty) == []
    # a folder with a file of the user's and the lock file of an earlier command: both stay
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    (mine / LOCK_NAME).write_text("")
    _run(case, mine, capsys)
    assert sorted(os.listdir(mine)) == [LOCK_NAME, "notes.txt"]


def test_a_folder_refused_for_its_results_keeps_no_lock_file_of_the_refusal(tmp_path):
    folder = tmp_path / "old"
    folder.mkdir()
    (folder / "summary.json").write_text('{"case": "x"}')
    with pytest.raises(InputError, match="already holds results"):
        claim_folder(folder, "run")
    assert os.listdir(folder) == ["summary.json"]


def test_a_lock_file_removed_by_a_refused_command_is_locked_again_on_the_new_file(tmp_path):
    """A process that opened the lock file just before a refused command removed it would
    lock a file no one else sees: it takes the lock again on the folder's new lock file, so
    that two processes never both hold the folder."""
    refused = FolderLock(tmp_path, "run").acquire()
    assert refused.created
    late = FolderLock(tmp_path, "run")
    stale = os.open(tmp_path / LOCK_NAME, os.O_RDWR)  # its open, before the removal
    opens = iter([(stale, False)])
    real_open = late._open
    late._open = lambda lock: next(opens, None) or real_open(lock)
    refused.release(remove=True)
    assert not (tmp_path / LOCK_NAME).exists()
    late.acquire()  # its flock on the removed file comes after the release
    assert (tmp_path / LOCK_NAME).is_file() and late.created
    with pytest.raises(InputError, match="is being written by another pacto process"):
        FolderLock(tmp_path, "resume").acquire()
    late.release()

"""The output-file policy: check before working, never half-written, modes, inputs are safe."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from ftcomp.errors import ParameterError
from ftcomp.io.atomic import atomic_output, atomic_write_text, check_writable, prepare_output_dir


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_a_new_file_gets_0666_less_the_umask_and_a_replaced_one_keeps_its_mode(
    tmp_path: Path,
) -> None:
    old = os.umask(0o027)
    try:
        atomic_write_text(tmp_path / "new.txt", "x")
    finally:
        os.umask(old)
    assert _mode(tmp_path / "new.txt") == 0o640
    kept = tmp_path / "kept.txt"
    kept.write_text("old")
    kept.chmod(0o604)
    atomic_write_text(kept, "new")
    assert kept.read_text() == "new" and _mode(kept) == 0o604


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "out.csv"
    target.write_text("old")
    with pytest.raises(KeyboardInterrupt), atomic_output(target) as tmp:
        tmp.write_text("half")
        raise KeyboardInterrupt
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_temporaries_a_killed_run_left_are_removed_on_the_next_write(tmp_path: Path) -> None:
    leftover = tmp_path / ".out.csv.k3j2.tmp"
    leftover.write_bytes(b"x" * 1000)
    atomic_write_text(tmp_path / "out.csv", "done")
    assert not leftover.exists() and (tmp_path / "out.csv").read_text() == "done"


def test_an_output_is_never_one_of_the_inputs_even_with_force(tmp_path: Path) -> None:
    source = tmp_path / "s.csv"
    source.write_text("fx\n")
    for spelled in (source, tmp_path / "." / "s.csv"):
        with pytest.raises(ParameterError, match="is also an input of this command"):
            check_writable(spelled, overwrite=True, inputs=[source])


@pytest.mark.parametrize(
    ("where", "message"),
    [
        ("parent_is_file/out.csv", "is a file, not a folder"),
        ("folder", "is a directory"),
    ],
)
def test_an_output_that_cannot_be_written_is_refused_before_any_work(
    tmp_path: Path, where: str, message: str
) -> None:
    (tmp_path / "parent_is_file").write_text("")
    (tmp_path / "folder").mkdir()
    with pytest.raises(ParameterError, match=message):
        check_writable(tmp_path / where, overwrite=True)


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs /proc")
def test_a_pseudo_filesystem_is_refused() -> None:
    with pytest.raises(ParameterError, match="cannot be written"):
        check_writable("/proc/ftcomp-out.csv", overwrite=False)


def test_an_existing_output_needs_force(tmp_path: Path) -> None:
    (tmp_path / "o.json").write_text("{}")
    with pytest.raises(ParameterError, match="pass overwrite=True"):
        check_writable(tmp_path / "o.json", overwrite=False)
    assert check_writable(tmp_path / "o.json", overwrite=True) == tmp_path / "o.json"


def test_an_output_folder_with_files_needs_force(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert prepare_output_dir(out, overwrite=False).is_dir()
    (out / "report.html").write_text("edited by hand")
    with pytest.raises(ParameterError, match="not empty; pass overwrite=True"):
        prepare_output_dir(out, overwrite=False)
    assert prepare_output_dir(out, overwrite=True) == out
    (tmp_path / "afile").write_text("")
    with pytest.raises(ParameterError, match="not a folder"):
        prepare_output_dir(tmp_path / "afile", overwrite=True)


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs /proc")
def test_a_folder_to_be_made_on_a_pseudo_filesystem_is_refused_even_for_root() -> None:
    # os.access says yes to root on /proc; only creating a file there tells the truth.
    with pytest.raises(ParameterError, match="cannot be written"):
        check_writable("/proc/ftcomp-x/out.csv", overwrite=False)
    with pytest.raises(ParameterError, match="cannot be written"):
        prepare_output_dir("/proc/ftcomp-x", overwrite=False)


def test_an_output_folder_can_be_checked_without_making_it(tmp_path: Path) -> None:
    out = tmp_path / "a" / "b"
    assert prepare_output_dir(out, overwrite=False, create=False) == out
    assert not (tmp_path / "a").exists()

"""Paths that are not regular files, on the command: an output that is a FIFO, a device, a folder or a
link to one is refused with one line and left as it was (never replaced by a regular file); a link to
a regular file is written through; standard input is refused as an input by name. Everything is made
in a temporary folder: the machine's /dev is never written."""
import os
import stat
import subprocess

import pytest

from conftest import run


def one_error_line(proc):
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    return lines[0]


def make_device(path):
    """/dev/null's numbers at `path`, where mknod is permitted (CAP_MKNOD); else skip."""
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("mknod is not permitted here (the FIFO and link cases run)")


@pytest.mark.parametrize("kind", ["fifo", "device", "folder", "link to a fifo", "link to a pipe", "link to nothing"])
@pytest.mark.parametrize("ext", [".binary", ".brdfz"])
def test_an_output_that_is_not_a_regular_file_is_refused_and_kept(cli, small_table, tmp_path, kind, ext):
    out = tmp_path / f"out{ext}"
    if kind == "fifo":
        os.mkfifo(out)
    elif kind == "device":
        make_device(out)
    elif kind == "folder":
        out.mkdir()
    elif kind == "link to a fifo":
        os.mkfifo(tmp_path / "fifo")
        out.symlink_to("fifo")
    elif kind == "link to a pipe":  # as /dev/stdout is, with the output piped
        out.symlink_to("/proc/self/fd/1")
    else:
        out.symlink_to("missing" + ext)
    before = os.lstat(out)
    proc = run(cli, "convert", small_table, out, "--res", "8x8x16", check=False)
    assert proc.returncode == 1 and "wrote" not in proc.stdout
    what = {"fifo": "is a FIFO", "device": "is a device", "folder": "is a folder",
            "link to a fifo": f"links to {tmp_path / 'fifo'}, which is a FIFO", "link to a pipe": "links to a pipe",
            "link to nothing": "is a symbolic link to a missing file"}[kind]
    line = one_error_line(proc)
    assert line.startswith(f"brdfz: {out}: {what}") and line.endswith("only regular files are written"), line
    after = os.lstat(out)
    assert stat.S_IFMT(after.st_mode) == stat.S_IFMT(before.st_mode) and after.st_ino == before.st_ino
    # Nothing beside it: no temporary, no file at a link's missing target.
    expected = [out.name, "fifo"] if kind == "link to a fifo" else [out.name]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(expected)


@pytest.mark.parametrize("ext", [".binary", ".brdfz", ".exr"])
def test_an_output_that_links_to_a_regular_file_is_written_through(cli, small_table, tmp_path, ext):
    (tmp_path / "data").mkdir()
    target = tmp_path / "data" / f"target{ext}"
    target.write_bytes(b"old")
    target.chmod(0o600)
    link = tmp_path / f"out{ext}"
    link.symlink_to(os.path.join("data", target.name))
    run(cli, "convert", small_table, link, "--res", "8x8x16")
    assert link.is_symlink() and os.readlink(link) == os.path.join("data", target.name)
    assert stat.S_IMODE(target.stat().st_mode) == 0o600
    assert run(cli, "eval", target, "--wi", "0,0,1", "--wo", "0,0.6,0.8").stdout.count(",") == 2  # it reads back
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", link.name]
    assert [p.name for p in (tmp_path / "data").iterdir()] == [target.name]


def test_standard_input_is_refused_as_an_input_by_name(cli, small_table, tmp_path):
    """A pipe on standard input (or "-") cannot be sized and checked before it is read: refused, not
    called a file with an unknown extension. Standard input redirected from a file is that file."""
    message = "standard input, pipes and devices are not read: give a file's name"
    for args, stdin in [(["info", "/dev/stdin"], subprocess.PIPE), (["info", "-"], subprocess.DEVNULL),
                        (["convert", "/dev/stdin", tmp_path / "x.binary"], subprocess.PIPE)]:
        proc = subprocess.run([cli, *map(str, args)], stdin=stdin, capture_output=True, text=True, timeout=60)
        assert proc.returncode == 1
        assert one_error_line(proc) == f"brdfz: {args[1]}: {message}"
    assert not (tmp_path / "x.binary").exists()
    with open(small_table, "rb") as f:
        redirected = subprocess.run([cli, "eval", "/dev/stdin", "--wi", "0,0,1", "--wo", "0,0.6,0.8"], stdin=f,
                                    capture_output=True, text=True, timeout=60)
    assert redirected.returncode == 0 and redirected.stdout.count(",") == 2

"""``fuzzynav data fetch | list`` and the dataset lookup, without the internet.

A local HTTP server (a thread) serves the maintainers' copies of the recordings
(``tests/conftest.py``: ``../shared/datasets``) laid out as on the raw-file host --
``owner/repo/commit/path`` -- through a tree of symlinks; ``$FUZZYNAV_DATA_URL`` points the
downloads at it.  Only the car drive (3.3 MB) and a few small A-KIT files are downloaded.
"""
import filecmp
import hashlib
import http.server
import socket
import threading
from pathlib import Path

import pytest

from fuzzynav.cli import main
from fuzzynav.errors import DataMissingError, InputFileError
from fuzzynav.realdata import datasets
from fuzzynav.realdata import fetch as fetch_mod
from fuzzynav.realdata.datasets import DATA_DIR_ENV, DATASETS, Dataset, load_registry
from fuzzynav.realdata.dataspec import parse_recording_spec, resolve
from fuzzynav.realdata.fetch import DATA_URL_ENV, FetchError, fetch
from fuzzynav.realdata.sources import data_options, parse_data_spec
from tests.conftest import datasets_dir

SHARED = datasets_dir()
pytestmark = pytest.mark.skipif(not (SHARED / "akit").is_dir()
                                or not (SHARED / "rtklib-drive").is_dir(),
                                reason=f"real recordings not found: {SHARED} (set FUZZYNAV_DATA)")
#: four small A-KIT files (trajectory 1's DVL and reference, both versions), 190 kB
TINY = Dataset("akit-tiny", "akit", "test subset", "https://github.com/ansfl/A-KIT", "-",
               tuple(f for f in DATASETS["akit"].files if f.path.endswith("trajectory1.csv")
                     and "IMU" not in f.path))


def _upstream_tree(root: Path) -> Path:
    """Symlinks ``root/<url path>`` -> the local copy of every registered file."""
    for ds in DATASETS.values():
        for f in ds.files:
            link = root / f.url
            link.parent.mkdir(parents=True, exist_ok=True)
            link.symlink_to(SHARED / ds.name / f.path)
    return root


class _Server:
    """A quiet ``http.server`` in a thread, recording the paths it was asked for."""

    def __init__(self, root: Path):
        requested = self.requested = []

        class Handler(http.server.SimpleHTTPRequestHandler):
            def __init__(self, *a, **kw):
                super().__init__(*a, directory=str(root), **kw)

            def do_GET(self):
                requested.append(self.path.lstrip("/"))
                super().do_GET()

            def log_message(self, *args):
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/"
        self.thread = threading.Thread(target=self.httpd.serve_forever,
                                       kwargs={"poll_interval": 0.02}, daemon=True)
        self.thread.start()

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def server(tmp_path, monkeypatch):
    """The upstream layout served locally; ``$FUZZYNAV_DATA_URL`` points at it, no retries."""
    srv = _Server(_upstream_tree(tmp_path / "upstream"))
    srv.root = tmp_path / "upstream"
    monkeypatch.setenv(DATA_URL_ENV, srv.url)
    monkeypatch.setattr(fetch_mod, "RETRIES", 0)
    monkeypatch.setitem(DATASETS, TINY.name, TINY)
    yield srv
    srv.close()


@pytest.fixture
def home(tmp_path, monkeypatch):
    """An empty data directory named by ``$FUZZYNAV_DATA``."""
    path = tmp_path / "data"
    monkeypatch.setenv(DATA_DIR_ENV, str(path))
    return path


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_registry_hashes_and_sizes_are_those_of_the_copies():
    """The shipped hashes, recomputed with hashlib from the maintainers' copies."""
    for ds in DATASETS.values():
        local = sorted(str(p.relative_to(SHARED / ds.name))
                       for p in (SHARED / ds.name).rglob("*") if p.is_file())
        assert sorted(f.path for f in ds.files) == local      # every file, nothing else
        for f in ds.files:
            assert _sha256(SHARED / ds.name / f.path) == f.sha256, f.path
            assert (SHARED / ds.name / f.path).stat().st_size == f.size_bytes
    assert len(DATASETS["akit"].files) == 8 * 5
    assert all("/Data/Trajectory" in f.url for f in DATASETS["akit"].files)


def test_fetch_downloads_verified_copies_and_then_downloads_nothing(server, home):
    lines = []
    directory = fetch("rtklib-drive", echo=lines.append)
    assert directory == home / "rtklib-drive"
    for f in DATASETS["rtklib-drive"].files:
        assert filecmp.cmp(directory / f.path, SHARED / "rtklib-drive" / f.path, shallow=False)
    assert len(server.requested) == 4 and all("downloaded" in s for s in lines)
    assert sorted(p.name for p in directory.iterdir()) == sorted(
        f.path for f in DATASETS["rtklib-drive"].files)          # no temporary files left
    lines.clear()
    fetch("rtklib-drive", echo=lines.append)
    assert len(server.requested) == 4                         # nothing downloaded again
    assert all("present, hash checked" in s for s in lines)


def test_corrupted_download_is_refused_and_nothing_kept(server, home):
    bad = TINY.files[1]
    served = server.root / bad.url
    data = bytearray(served.read_bytes())
    data[100] ^= 1                                            # one bit flipped
    served.unlink()
    served.write_bytes(bytes(data))
    target = home / TINY.name / bad.path
    target.parent.mkdir(parents=True)
    target.write_bytes(bytes(data[:500]))                     # a wrong copy already there
    with pytest.raises(FetchError, match="SHA-256") as err:
        fetch(TINY.name)
    assert bad.url in str(err.value) and "\n" not in str(err.value)
    assert not target.exists()
    # the file before it was kept, verified; no temporary file of the refused download
    assert [p.name for p in target.parent.iterdir()] == [Path(TINY.files[0].path).name]


def test_interrupted_fetch_resumes_with_the_missing_and_cut_files(server, home):
    """A file cut by an interrupted download is found by its hash and fetched again; the
    complete ones are not downloaded (pooch resumes file by file, not mid-file)."""
    first, cut = TINY.files[0], TINY.files[2]
    for f, n in ((first, None), (cut, 3000)):
        p = home / TINY.name / f.path
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes((SHARED / "akit" / f.path).read_bytes()[:n])
    fetch(TINY.name, echo=lambda _: None)
    assert sorted(server.requested) == sorted(f.url for f in TINY.files if f is not first)
    for f in TINY.files:
        assert _sha256(home / TINY.name / f.path) == f.sha256


def test_a_file_missing_on_the_server_is_one_line_with_the_status(server, home):
    (server.root / TINY.files[0].url).unlink()
    with pytest.raises(FetchError, match=r"\(HTTP 404\)") as err:
        fetch(TINY.name)
    assert TINY.files[0].url in str(err.value) and "\n" not in str(err.value)
    assert not (home / TINY.name).exists()                # nothing written


def _dead_url() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    return f"http://127.0.0.1:{port}/"                        # nothing listens there now


def test_offline_fetch_is_one_line_saying_what_to_download_and_where(home, monkeypatch,
                                                                    capsys):
    monkeypatch.setenv(DATA_URL_ENV, _dead_url())
    monkeypatch.setattr(fetch_mod, "RETRIES", 0)
    assert main(["data", "fetch", "akit"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert "cannot download" in err and "no connection" in err
    assert "fuzzynav data list akit --files" in err and str(home / "akit") in err
    assert not (home / "akit").exists()                       # not even an empty directory
    assert not home.exists()  # nor the data directory $FUZZYNAV_DATA named, made for it
    home.mkdir()  # a data directory that was there before stays
    assert main(["data", "fetch", "akit"]) == 2
    assert home.is_dir() and not (home / "akit").exists()


def test_data_list_says_size_presence_and_where(home, capsys):
    assert main(["data", "list"]) == 0
    out = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line for line in out[1:]}
    assert set(rows) == {"akit", "rtklib-drive"}
    for name, row in rows.items():
        mb = sum(p.stat().st_size for p in (SHARED / name).rglob("*") if p.is_file()) / 1e6
        assert f"{mb:.1f} MB" in row
        assert f"missing: fuzzynav data fetch {name} (into {home / name})" in row
    drive = home / "rtklib-drive"
    drive.mkdir(parents=True)
    for f in DATASETS["rtklib-drive"].files:
        (drive / f.path).symlink_to(SHARED / "rtklib-drive" / f.path)
    main(["data", "list", "rtklib-drive"])
    assert f"present: {drive}" in capsys.readouterr().out
    (drive / "LICENSE").unlink()
    main(["data", "list", "rtklib-drive"])
    assert "incomplete (1 of 4 files" in capsys.readouterr().out
    main(["data", "list", "akit", "--files"])
    files = capsys.readouterr().out.splitlines()
    assert len(files) == 40 and files[0].split()[1].startswith("https://raw.githubusercontent")


def test_a_system_directory_is_refused_before_any_download(server, capsys):
    target = Path("/etc/fuzzynav-test-must-not-exist")
    assert main(["data", "fetch", "rtklib-drive", "--dest", str(target)]) == 2
    assert str(target) in capsys.readouterr().err
    assert not target.exists() and server.requested == []


def test_unknown_dataset_is_one_line(home, capsys):
    assert main(["data", "fetch", "kitti"]) == 2
    assert "unknown dataset 'kitti'; known: akit, rtklib-drive" in capsys.readouterr().err


def test_data_rtklib_drive_resolves_through_the_user_cache(server, tmp_path, monkeypatch,
                                                          capsys):
    cache = tmp_path / "cache"
    monkeypatch.delenv(DATA_DIR_ENV, raising=False)
    monkeypatch.setattr(datasets, "user_cache_dir", lambda: cache)
    monkeypatch.setattr(datasets, "dev_data_dir", lambda: None)
    assert main(["run", "--data", "rtklib-drive", "--filter", "ekf"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "fuzzynav data fetch rtklib-drive" in err
    assert str(cache) in err
    assert main(["data", "fetch", "rtklib-drive"]) == 0
    assert "not where fuzzynav looks" not in capsys.readouterr().out
    source, directory, session = parse_data_spec("rtklib-drive")
    assert (source.kind, directory, session) == ("rtklib", cache / "rtklib-drive", None)
    assert data_options("rtklib-drive?min_speed=0.5").min_speed_mps == 0.5
    spec = parse_recording_spec("rtklib-drive@0-50%")
    assert str(spec) == "rtklib:rtklib-drive@0-50%" and resolve(spec) == cache / "rtklib-drive"
    with pytest.raises(DataMissingError, match="fuzzynav data fetch akit"):
        parse_data_spec("akit:3")


def test_lookup_order_and_the_long_forms(tmp_path, monkeypatch):
    cache, dev = tmp_path / "cache", tmp_path / "dev"
    monkeypatch.setattr(datasets, "user_cache_dir", lambda: cache)
    monkeypatch.setattr(datasets, "dev_data_dir", lambda: dev)
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path / "env"))
    assert datasets.data_dirs() == [tmp_path / "env"]         # it overrides, alone
    monkeypatch.delenv(DATA_DIR_ENV)
    assert datasets.data_dirs() == [cache, dev]
    (cache / "rtklib-drive").mkdir(parents=True)              # an empty (interrupted) copy
    assert datasets.find_directory("rtklib-drive") == cache / "rtklib-drive"
    (dev / "rtklib-drive").mkdir(parents=True)
    for f in DATASETS["rtklib-drive"].files:
        (dev / "rtklib-drive" / f.path).symlink_to(SHARED / "rtklib-drive" / f.path)
    assert datasets.find_directory("rtklib-drive") == dev / "rtklib-drive"   # the complete
    # akit:N is the dataset; akit:DIR and akit:DIR:N and a directory named like a session
    # keep their meaning
    (cache / "akit").mkdir()
    assert parse_data_spec("akit:1-3")[1:] == (cache / "akit", "1-3")
    assert parse_data_spec(f"akit:{SHARED / 'akit'}:2")[1:] == (SHARED / "akit", "2")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "4").mkdir()
    assert parse_data_spec("akit:4")[1:] == (Path("4"), None)
    assert str(parse_recording_spec("akit:3@0-50%")) == "akit:akit:3@0-50%"


def test_a_damaged_registry_names_the_field(tmp_path):
    path = tmp_path / "datasets.json"
    path.write_text('{"datasets": {"x": {"kind": "akit", "description": "", "source": "", '
                    '"licence": "", "files": [{"path": "../a", "url": "u", "size_bytes": 1, '
                    '"sha256": "' + "0" * 64 + '"}]}}}')
    with pytest.raises(InputFileError, match=r"\$\.datasets\.x\.files\[0\]\.path"):
        load_registry(path)

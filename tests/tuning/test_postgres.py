"""A study shared through a real PostgreSQL server: a throwaway one on loopback.

The server runs from a temporary directory (``initdb``, a free port on 127.0.0.1, Unix
socket in that directory) and is stopped and deleted at the end.  PostgreSQL refuses to run
as root, so as root it runs as the ``postgres`` user (or ``nobody``) through ``runuser``.
Skips, saying why, when no server binaries are installed (``.ci/run`` installs them).
"""
from __future__ import annotations

import glob
import os
import pwd
import shutil
import socket
import subprocess
import tempfile
from pathlib import Path

import pytest
from optuna.trial import TrialState

from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
from fuzzynav.tuning.optuna_study import open_study
from tests.tuning.studies import write_study


def server_bin_dir():
    """The directory of ``initdb`` / ``pg_ctl`` (PATH first, then the Debian layout)."""
    found = shutil.which("initdb")
    if found and shutil.which("pg_ctl", path=str(Path(found).resolve().parent)):
        return Path(found).resolve().parent
    for d in sorted(glob.glob("/usr/lib/postgresql/*/bin"), reverse=True):
        if os.access(Path(d) / "initdb", os.X_OK) and os.access(Path(d) / "pg_ctl", os.X_OK):
            return Path(d)
    return None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _as_server_user(argv, user):
    return ["runuser", "-u", user, "--", *argv] if user else argv


@pytest.fixture(scope="module")
def postgres_url():
    bin_dir = server_bin_dir()
    if bin_dir is None:
        pytest.skip("no PostgreSQL server binaries (initdb, pg_ctl) on PATH or in "
                    "/usr/lib/postgresql/*/bin; .ci/run installs the postgresql package")
    pytest.importorskip("psycopg2", reason="the PostgreSQL driver psycopg2 is not installed "
                                           "(pip install -e '.[studies]')")
    user = None
    if os.geteuid() == 0:  # postgres refuses root
        user = next((u for u in ("postgres", "nobody") if _has_user(u)), None)
        if user is None or not shutil.which("runuser"):
            pytest.skip("running as root without a 'postgres' or 'nobody' user and runuser")
    root = Path(tempfile.mkdtemp(prefix="fuzzynav-pg-"))
    if user:
        pw = pwd.getpwnam(user)
        os.chown(root, pw.pw_uid, pw.pw_gid)
    data, port = root / "data", _free_port()
    run = dict(check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=root)
    subprocess.run(_as_server_user([str(bin_dir / "initdb"), "-D", str(data), "-A", "trust",
                                    "-U", "fuzzynav", "-E", "UTF8", "--no-locale"], user),
                   **run)
    opts = f"-h 127.0.0.1 -p {port} -k {root} -c fsync=off -c full_page_writes=off"
    subprocess.run(_as_server_user([str(bin_dir / "pg_ctl"), "-D", str(data), "-w", "-t", "60",
                                    "-l", str(root / "server.log"), "-o", opts, "start"], user),
                   **run)
    try:
        import psycopg2

        conn = psycopg2.connect(host="127.0.0.1", port=port, user="fuzzynav",
                                dbname="postgres")
        conn.autocommit = True
        conn.cursor().execute("CREATE DATABASE fuzzynav_studies")
        conn.close()
        yield f"postgresql://fuzzynav@127.0.0.1:{port}/fuzzynav_studies"
    finally:
        subprocess.run(_as_server_user([str(bin_dir / "pg_ctl"), "-D", str(data), "-m", "immediate",
                                        "-w", "stop"], user),
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=root)
        shutil.rmtree(root, ignore_errors=True)


def _has_user(name) -> bool:
    try:
        pwd.getpwnam(name)
    except KeyError:
        return False
    return True


def test_two_workers_share_a_study_through_postgresql(tmp_path, sim_cache, postgres_url):
    cfg = load_study_config(write_study(tmp_path, study={"trials": 8}))
    study = run_study(cfg, workers=2, storage=postgres_url, cache_dir=sim_cache,
                      progress=False)
    trials = study.get_trials(deepcopy=False)
    assert [t.state for t in trials] == [TrialState.COMPLETE] * 8
    assert len({tuple(sorted(t.params.items())) for t in trials}) == 8
    assert not (tmp_path / "tiny.journal").exists()  # nothing went to the default storage
    # another process (another machine, in real use) sees and resumes the same study
    again = run_study(cfg, trials=10, storage=postgres_url, cache_dir=sim_cache,
                      progress=False)
    assert [t.params for t in again.trials[:8]] == [t.params for t in trials]
    assert len(again.trials) == 10
    # the study opened by URL is the one the CLI's export/report would use
    assert len(open_study(cfg, postgres_url).trials) == 10


@pytest.mark.parametrize("kind", ["baselines", "alignment"])
def test_baseline_and_alignment_studies_share_postgresql_too(tmp_path, sim_cache, postgres_url,
                                                             kind):
    """The other study kinds run on the same driver: two workers through PostgreSQL, then
    resumed from there; nothing goes to the default journal file."""
    from fuzzynav.tuning.kinds import load_plan
    from fuzzynav.tuning.study_run import run_plan
    from tests.tuning.test_study_kinds import BASELINE, _alignment_study

    if kind == "baselines":
        path = tmp_path / "bl.toml"
        path.write_text(BASELINE.replace('name = "bl"', f'name = "bl_{os.getpid()}"'))
    else:
        path = _alignment_study(tmp_path, name=f"al_{os.getpid()}")
    plan = load_plan(path, sim_cache)
    studies, _ = run_plan(plan, 2, 2, postgres_url, progress=False)
    (part, study), = studies.items()
    first = study.get_trials()
    assert [t.state for t in first] == [TrialState.COMPLETE] * 2
    studies, _ = run_plan(load_plan(path, sim_cache), 3, 1, postgres_url, progress=False)
    trials = studies[part].get_trials()
    assert [t.params for t in trials[:2]] == [t.params for t in first]
    assert len(trials) == 3 and not list(tmp_path.glob("*.journal"))
    assert len(open_study(plan.config(part), postgres_url).trials) == 3


def test_a_refused_new_study_is_removed_from_postgresql(tmp_path, sim_cache, postgres_url):
    """A new study whose first trial is refused is deleted from the database; the other
    studies there stay."""
    import optuna

    from fuzzynav.errors import FuzzynavError
    from fuzzynav.tuning.optuna_study import make_storage

    name = f"refused_{os.getpid()}"
    cfg = load_study_config(write_study(
        tmp_path, name=name,
        objective={"weights": {"pos": 1.0, "vel": 1.0, "att": 1.0, "r_use": 0.1}}))
    before = optuna.get_all_study_names(make_storage(postgres_url, heartbeat=False))
    with pytest.raises(FuzzynavError, match="'r_use' has weight"):
        run_study(cfg, trials=2, storage=postgres_url, cache_dir=sim_cache, progress=False)
    after = optuna.get_all_study_names(make_storage(postgres_url, heartbeat=False))
    assert name not in after and sorted(after) == sorted(before)

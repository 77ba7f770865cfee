"""``fuzzynav data list | fetch``: the public recordings, where they are, downloading them."""
from __future__ import annotations

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("data", help="public recordings: list them, fetch them")
    ds = p.add_subparsers(dest="data_command", metavar="ACTION")
    ds.required = True
    ls = ds.add_parser("list", help="the datasets: size, whether present and where")
    ls.add_argument("name", nargs="?", help="one dataset (default: all)")
    ls.add_argument("--files", action="store_true",
                    help="list each file: its path in the dataset, URL and SHA-256")
    ls.set_defaults(func=_cmd_list)
    f = ds.add_parser("fetch", help="download a dataset (SHA-256 checked) into the data "
                                    "directory ($FUZZYNAV_DATA, else the user cache)")
    f.add_argument("name", help="dataset name (fuzzynav data list)")
    f.add_argument("--dest", metavar="DIR",
                   help="data directory to write into instead (files go to DIR/NAME/)")
    f.set_defaults(func=_cmd_fetch)


def _selected(name):
    from fuzzynav.realdata.datasets import DATASETS
    from fuzzynav.realdata.fetch import get_dataset

    return [get_dataset(name)] if name is not None else list(DATASETS.values())


def _cmd_list(args) -> int:
    from fuzzynav.realdata.datasets import fetch_home
    from fuzzynav.realdata.fetch import base_url, dataset_status

    chosen = _selected(args.name)
    if args.files:
        url = base_url()
        for d in chosen:
            for f in d.files:
                print(f"{d.name}/{f.path}  {url}{f.url}  sha256:{f.sha256}")
        return 0
    print(f"{'dataset':<14}{'kind':<8}{'files':>6}{'size':>10}  status")
    for d in chosen:
        path, missing = dataset_status(d)
        if path is None:
            state = f"missing: fuzzynav data fetch {d.name} (into {fetch_home() / d.name})"
        elif missing:
            state = (f"incomplete ({missing} of {len(d.files)} files missing or cut): "
                     f"{path}; fuzzynav data fetch {d.name}")
        else:
            state = f"present: {path}"
        print(f"{d.name:<14}{d.kind:<8}{len(d.files):>6}{d.size_bytes / 1e6:>7.1f} MB  {state}")
    return 0


def _cmd_fetch(args) -> int:
    from fuzzynav.realdata.datasets import data_dirs
    from fuzzynav.realdata.fetch import fetch, get_dataset

    ds = get_dataset(args.name)
    directory = fetch(ds.name, dest=args.dest)
    print(f"{ds.name}: {len(ds.files)} files in {directory} ({ds.licence})")
    if directory.parent.resolve() not in [b.resolve() for b in data_dirs()]:
        print(f"{ds.name}: not where fuzzynav looks: set FUZZYNAV_DATA={directory.parent} "
              f"or name the directory (--data {ds.kind}:{directory})")
    return 0

"""Fill the labelled-scan cache from local git copies of the repositories the scans come from.

Usage: python tools/scans_from_mirrors.py OWNER/NAME=GIT_DIR [OWNER/NAME=GIT_DIR ...]

:func:`superfacets.evaluation.datasets.scans.fetch_scan` downloads each scan file from
its repository at a pinned commit. Where that host cannot be reached but a clone (or a
bare mirror) of the repository is at hand, this reads each file of
:data:`~superfacets.evaluation.datasets.scans.SCANS` from the clone at the same commit
(``git cat-file``), checks its SHA-256 and writes it into the cache
(``$SUPERFACETS_SCANS``, by default ``~/.cache/superfacets/scans``), where
``load_scan``, ``benchmarks/real_scans.py`` and ``tests/evaluation/test_scans.py`` find it. The
files stay outside the repository. Example::

    python tools/scans_from_mirrors.py isl-org/Open3D-ML=~/src/Open3D-ML \\
        open-mmlab/mmdetection3d=~/src/mmdetection3d PDAL/PDAL=~/src/PDAL \\
        r-lidar/lidR=~/src/lidR PointCloudLibrary/data=~/src/pcl-data \\
        kccushman/SERC_lidarComparison=~/src/SERC_lidarComparison
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

from superfacets.evaluation.datasets.scans import SCANS, scan_cache

_PREFIX = "https://raw.githubusercontent.com/"


def main(argv: list[str]) -> int:
    mirrors = {}
    for arg in argv:
        repo, sep, folder = arg.partition("=")
        if not sep:
            print(f"not OWNER/NAME=GIT_DIR: {arg}", file=sys.stderr)
            return 2
        mirrors[repo] = Path(folder).expanduser()
    cache = scan_cache()
    cache.mkdir(parents=True, exist_ok=True)
    missing = 0
    for scan in SCANS.values():
        for name, url, sha in scan.files:
            owner, repo, commit, path = url[len(_PREFIX):].split("/", 3)
            dest = cache / name
            if dest.exists():
                print(f"{name}: already in the cache")
                continue
            git = mirrors.get(f"{owner}/{repo}")
            if git is None:
                print(f"{name}: no copy of {owner}/{repo} given")
                missing += 1
                continue
            got = subprocess.run(["git", "-C", str(git), "cat-file", "-p", f"{commit}:{path}"],
                                 capture_output=True)
            if got.returncode or hashlib.sha256(got.stdout).hexdigest() != sha:
                why = "not at the pinned commit" if got.returncode else "SHA-256 differs"
                print(f"{name}: {why} in {git}")
                missing += 1
                continue
            tmp = dest.with_name(dest.name + ".part")
            tmp.write_bytes(got.stdout)
            tmp.replace(dest)
            print(f"{name}: {len(got.stdout):,} bytes written")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

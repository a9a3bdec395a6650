"""Pack a finished study folder's replicates (``replicates/``, one JSON each) into one
gzipped file, ``replicates.jsonl.gz`` (``bayes_inerter.study.replicate_store``), or unpack them
again. Every study reads both, and a run continued into a packed folder writes its new
replicates loose beside the packed file; pack a folder once its run is done.

    python studies/pack_replicates.py FOLDER [FOLDER ...] [--unpack]

Prints each folder with the number of replicates its packed file holds. Exit codes: 0
done, 2 a folder that does not exist or holds no replicate (the others are still done).
"""

import argparse
import sys
from pathlib import Path

from bayes_inerter.study.replicate_store import pack, unpack


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path, help="study output folders")
    parser.add_argument("--unpack", action="store_true", help="write the packed replicates back to replicates/")
    args = parser.parse_args(argv)
    status = 0
    for folder in args.folders:
        if not folder.is_dir():
            print(f"error: {folder} is not a folder; name a study's output folder", file=sys.stderr)
            status = 2
            continue
        try:
            n = unpack(folder) if args.unpack else pack(folder)
        except ValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            status = 2
            continue
        print(f"{folder}: {n} replicates {'unpacked' if args.unpack else 'packed'}")
    return status


if __name__ == "__main__":
    sys.exit(main())

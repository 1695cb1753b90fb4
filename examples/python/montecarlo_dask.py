"""A Monte Carlo table split into shards on a Dask cluster (docs/montecarlo.md).

    python examples/python/montecarlo_dask.py                   # a LocalCluster on this machine
    python examples/python/montecarlo_dask.py --scheduler tcp://host:8786 --shards 64

Each task runs one shard in-process and returns its partial result as a dict;
obsan.montecarlo_merge reduces them into the table a single run would print.
"""

import argparse
from typing import Any

import obsan
from dask.distributed import Client, LocalCluster


def shard(k: int, n: int, table: int, runs: int, seed: int) -> Any:
    return obsan.montecarlo(table=table, runs=runs, seed=seed, threads=1, shard=(k, n))


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--scheduler", help="a running scheduler's address (default: a LocalCluster)")
    ap.add_argument("--shards", type=int, default=64)
    ap.add_argument("--table", type=int, default=5)
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster processes")
    a = ap.parse_args()
    # dask.distributed has no type annotations: its calls are untyped for mypy --strict.
    if a.scheduler:
        client = Client(a.scheduler)  # type: ignore[no-untyped-call]
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1)  # type: ignore[no-untyped-call]
        client = Client(cluster)  # type: ignore[no-untyped-call]
    with client:
        futures = [
            client.submit(shard, k, a.shards, a.table, a.runs, a.seed, pure=True)
            for k in range(1, a.shards + 1)
        ]
        tables = obsan.montecarlo_merge(client.gather(futures))  # type: ignore[no-untyped-call]
    for cell in tables[0]["cells"]:
        ls = next(m for m in cell["methods"] if m["method"] == "LS")
        print(cell["label"], ls["mean_abs_error"])


# Dask's worker processes import this file again: without the guard each would start a
# cluster of its own ("Nanny failed to start").
if __name__ == "__main__":
    main()

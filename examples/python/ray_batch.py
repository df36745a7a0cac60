"""Fan a large batch of candidate grasps out over a Ray cluster.

Each Ray task solves one chunk with ``grasp_torque.solve_batch`` (all the task's cores,
the GIL released); the driver puts the arrays in Ray's object store once and gathers
the chunks in order. ``ray.init()`` starts a local cluster; pass ``--address auto`` to
join a running one.

    pip install ./python "ray[default]"
    python examples/python/ray_batch.py --grasps 1000000 --chunks 32

It prints the throughput; ``--check`` also solves the batch locally and compares.
"""

import argparse
import time

import numpy as np
import ray

import grasp_torque as gt

CONTACTS = [{"model": "pcwf", "mu": 0.7}] * 3


@ray.remote
def solve_chunk(G, JT, W, threads):
    # Arrays from the object store are read-only views: solve_batch only reads them.
    out = gt.solve_batch(G, JT, W, CONTACTS, threads=threads)
    return out.torque, out.objective, out.status


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grasps", type=int, default=200_000)
    ap.add_argument("--wrenches", type=int, default=0, help="K load directions per grasp")
    ap.add_argument("--chunks", type=int, default=16)
    ap.add_argument("--threads-per-task", type=int, default=1)
    ap.add_argument("--address", default=None, help="a running cluster (default: start one)")
    ap.add_argument("--check", action="store_true", help="compare with a local batch")
    args = ap.parse_args()

    G, JT, W = gt.synthetic_grasps(args.grasps, wrenches=args.wrenches, seed=0)
    ray.init(address=args.address, include_dashboard=False, log_to_driver=False)
    cpus = int(ray.cluster_resources().get("CPU", 1))
    refs_in = [
        (ray.put(g), ray.put(j), ray.put(w))
        for g, j, w in zip(
            np.array_split(G, args.chunks), np.array_split(JT, args.chunks), np.array_split(W, args.chunks)
        )
    ]
    task = solve_chunk.options(num_cpus=args.threads_per_task)
    # Warm the workers (import, first task) so the figure is the steady state.
    ray.get([task.remote(*r, args.threads_per_task) for r in refs_in[: min(cpus, len(refs_in))]])
    start = time.perf_counter()
    parts = ray.get([task.remote(*r, args.threads_per_task) for r in refs_in])
    elapsed = time.perf_counter() - start
    torque = np.concatenate([p[0] for p in parts])
    objective = np.concatenate([p[1] for p in parts])
    status = np.concatenate([p[2] for p in parts])
    solves = status.size
    optimal = int((status == 0).sum())
    print(
        f"{args.grasps} grasps, {solves} solves on {cpus} CPUs in {elapsed:.3f} s: "
        f"{args.grasps / elapsed:,.0f} grasps/s, {solves / elapsed:,.0f} solves/s; "
        f"{optimal} optimal"
    )
    if args.check:
        local = gt.solve_batch(G, JT, W, CONTACTS)
        np.testing.assert_array_equal(status, local.status)
        np.testing.assert_array_equal(objective, local.objective)
        np.testing.assert_array_equal(torque, local.torque)
        print("the Ray result matches the local batch")
    ray.shutdown()


if __name__ == "__main__":
    main()

"""Where the runs of `make dse` execute: Ray actors (one Evaluator with its JVM each) on a local Ray instance
with WORKERS cpus, or on the cluster RAY_ADDRESS names; WORKERS=0 runs them inline (no Ray, for debugging)."""
import os

from .knobs import ROOT
from .worker import Evaluator


class Pool:
    def __init__(self, workers, address, java, log_dir, work=None):
        """work: the Verilator build folder of a single worker (default: build/sim-dse/<worker>); only one
        worker may use a given folder, so it is refused with more."""
        self.inline = workers == 0 and not address
        self.log_dir, self.java = log_dir, java
        if work and (address or workers > 1):
            raise ValueError("a shared Verilator build folder needs a single local worker")
        if self.inline:
            self.actors = [Evaluator(java, log_dir, "w0", work)]
            return
        import ray

        self.ray = ray
        self.started = not ray.is_initialized()
        if self.started:
            # the workers import dse from the project tree at the same path (docs/dse.md: what a cluster node needs)
            env = {"env_vars": {"PYTHONPATH": ROOT}}
            if address:
                ray.init(address=address, runtime_env=env, logging_level="ERROR", log_to_driver=False)
            else:
                # address="local": a RAY_ADDRESS in the environment must not turn a local run into a cluster run
                ray.init(address="local", num_cpus=workers, include_dashboard=False, runtime_env=env, logging_level="ERROR",
                         log_to_driver=False)
        n = workers or int(ray.cluster_resources().get("CPU", 1))
        self.remote = ray.remote(num_cpus=1, max_restarts=-1)(Evaluator)
        self.actors = [self.remote.remote(java, log_dir, f"w{i}", work) for i in range(n)]

    @property
    def size(self):
        return len(self.actors)

    def map(self, tasks):
        """Yields one result per task as each finishes (in completion order). A worker lost mid-task (its process
        died) yields a crash result for that task; Ray restarts the actor for the next one."""
        tasks = list(tasks)
        if self.inline:
            for t in tasks:
                yield self.actors[0].run(t)
            return
        ray = self.ray
        free, running, todo = list(self.actors), {}, list(reversed(tasks))
        while todo or running:
            while free and todo:
                a, t = free.pop(), todo.pop()
                running[a.run.remote(t)] = (a, t)
            done, _ = ray.wait(list(running), num_returns=1)
            a, t = running.pop(done[0])
            free.append(a)
            try:
                yield ray.get(done[0])
            except ray.exceptions.RayError as e:
                msg = " ".join(str(e).split())[:300]
                yield {"key": t["key"], "answer": {"status": 1, "result": None, "error": f"worker lost: {msg}"},
                       "wall_s": 0.0, "worker": "?"}

    def stats(self):
        if self.inline:
            return [a.stats() for a in self.actors]
        return self.ray.get([a.stats.remote() for a in self.actors])

    def close(self):
        if self.inline:
            for a in self.actors:
                a.stop()
            return
        try:
            self.ray.get([a.stop.remote() for a in self.actors], timeout=30)
        except Exception:  # noqa: BLE001 - a worker that cannot stop cleanly is killed below anyway
            pass
        for a in self.actors:
            self.ray.kill(a)
        if self.started:
            self.ray.shutdown()

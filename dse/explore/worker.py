"""Long-lived evaluators of `make dse`: each holds one JVM running rtaccel.cli.Serve (JSON lines) and keeps it
between runs, so scenes, trees and access traces are parsed and built once per worker, not once per point.

`Evaluator` is a plain class; dse.explore.explore wraps it as a Ray actor (one per worker) or uses it inline.
"""
import json
import os
import selectors
import subprocess
import time
from collections import deque

from .knobs import ROOT


class JvmServer:
    """rtaccel.cli.Serve in a subprocess. A JVM that dies or stops answering is reported as a crash of the
    request that was running and started again for the next one."""

    def __init__(self, java, log_path, timeout_s=3600):
        self.java, self.log_path, self.timeout_s = java, log_path, timeout_s
        self.proc, self.starts, self.start_s = None, 0, 0.0

    def _start(self):
        self.log = open(self.log_path, "a")
        self.proc = subprocess.Popen(["bash", "-c", f"exec {self.java} rtaccel.cli.Serve"], cwd=ROOT, text=True,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log, bufsize=1)
        self.starts += 1

    def _tail(self, n=5):
        try:
            with open(self.log_path) as f:
                return " | ".join(l.strip() for l in deque(f, maxlen=n) if l.strip())
        except OSError:
            return ""

    def request(self, cmd, args):
        """The server's answer {"status", "result", "error", "wall_s", ...}; status 1 for a crash or a timeout."""
        fresh = self.proc is None or self.proc.poll() is not None
        if fresh:
            self._start()
        t0 = time.time()
        try:
            self.proc.stdin.write(json.dumps({"cmd": cmd, "args": [str(a) for a in args]}) + "\n")
            self.proc.stdin.flush()
            with selectors.DefaultSelector() as sel:
                sel.register(self.proc.stdout, selectors.EVENT_READ)
                line = self.proc.stdout.readline() if sel.select(self.timeout_s) else None
        except (BrokenPipeError, OSError):
            line = ""
        if line is None:
            self.stop()
            return {"status": 1, "result": None, "error": f"no answer within {self.timeout_s} s; the JVM was stopped"}
        if not line:
            rc = self.proc.wait()
            self.proc = None
            return {"status": 1, "result": None, "error": f"the JVM exited with status {rc}: {self._tail()}"}
        try:
            answer = json.loads(line)
            if fresh:  # JVM start-up = what the first answer took beyond the command's own time
                self.start_s += max(0.0, time.time() - t0 - answer.get("wall_s", 0.0))
            return answer
        except json.JSONDecodeError:
            return {"status": 1, "result": None, "error": f"the JVM answered no JSON: {line[:200]}"}

    def stop(self):
        if self.proc is not None and self.proc.poll() is None:
            self.proc.stdin.close()  # Serve ends at the end of its input
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None


class Evaluator:
    """One worker: runs tasks {"key", "cmd", "args"} on its JVM and returns {"key", "answer", "wall_s", "worker"}."""

    def __init__(self, java, log_dir, name, work=None):
        os.makedirs(log_dir, exist_ok=True)
        self.name = name
        self.work = work or os.path.join("build", "sim-dse", name)  # Verilator builds, cached per circuit
        self.jvm = JvmServer(java, os.path.join(log_dir, f"{name}.log"))

    def run(self, task):
        t0 = time.time()
        args = list(task["args"])
        if task["cmd"] == "simulate":  # one Verilator build folder per worker: two builds must not share one
            args += ["--work", self.work]
        answer = self.jvm.request(task["cmd"], args)
        return {"key": task["key"], "answer": answer, "wall_s": time.time() - t0, "worker": self.name}

    def stats(self):
        return {"worker": self.name, "jvm_starts": self.jvm.starts, "jvm_start_s": self.jvm.start_s}

    def stop(self):
        self.jvm.stop()
        return True

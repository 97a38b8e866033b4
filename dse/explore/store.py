"""The results store of `make dse`: one SQLite row per point x scene x fidelity.

A row's key is a hash of (configuration, scene, rays, fidelity, rtaccel version), so a rerun finds what is done
and evaluates only the rest; each row is committed as soon as its run ends, so a killed sweep loses at most the
runs in flight. Failed runs are rows too (status refused / check_failed / crashed / skipped, with the error):
they are data, and they are never read as results.
"""
import hashlib
import json
import sqlite3
import time

OK, REFUSED, CHECK_FAILED, CRASHED, SKIPPED = "ok", "refused", "check_failed", "crashed", "skipped"
STATUS_OF_EXIT = {0: OK, 2: REFUSED, 3: CHECK_FAILED}
FAILED = (REFUSED, CHECK_FAILED, CRASHED)  # what the JSON's "failed" counts; skipped and infeasible are not failures

SCHEMA = """
CREATE TABLE IF NOT EXISTS runs (
  key TEXT PRIMARY KEY, space TEXT, point TEXT, config TEXT, scene TEXT, rays TEXT, fidelity TEXT,
  rtaccel TEXT, status TEXT, exit INTEGER, error TEXT, result TEXT, wall_s REAL, finished REAL)
"""


def point_id(config):
    """A short stable name of a configuration {KNOB: value}."""
    return hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()[:10]


def run_key(config, scene, rays, fidelity, version):
    return hashlib.sha256(json.dumps([config, scene, rays, fidelity, version], sort_keys=True).encode()).hexdigest()


class Store:
    def __init__(self, path):
        self.path = path
        self.db = sqlite3.connect(path)
        self.db.execute("PRAGMA journal_mode=WAL")  # readers (tests, a second look) never block the sweep
        self.db.execute(SCHEMA)
        self.db.commit()

    def get(self, key):
        r = self.db.execute("SELECT status, exit, error, result, wall_s FROM runs WHERE key = ?", (key,)).fetchone()
        if r is None:
            return None
        return {"status": r[0], "exit": r[1], "error": r[2], "result": json.loads(r[3]) if r[3] else None, "wall_s": r[4]}

    def put(self, key, space, config, scene, rays, fidelity, version, status, exit_code, error, result, wall_s):
        self.db.execute("INSERT OR REPLACE INTO runs VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
                        (key, space, point_id(config), json.dumps(config, sort_keys=True), scene, rays, fidelity,
                         version, status, exit_code, error, json.dumps(result) if result is not None else None,
                         wall_s, time.time()))
        self.db.commit()

    def rows(self, space=None):
        q = "SELECT point, config, scene, fidelity, status, exit, error, result, wall_s FROM runs"
        cur = self.db.execute(q + (" WHERE space = ?" if space else "") + " ORDER BY finished", (space,) if space else ())
        return [dict(point=p, config=json.loads(c), scene=s, fidelity=f, status=st, exit=e, error=er,
                     result=json.loads(r) if r else None, wall_s=w) for p, c, s, f, st, e, er, r, w in cur]

    def close(self):
        self.db.close()

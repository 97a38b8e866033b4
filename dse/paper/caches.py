"""python -m dse.paper.caches --scene MESH --tris TRIS.npy --rays RAYS.npy --out DIR [--java CMD] [--m 4]
       [--mppl 4] [--mppl-list 1,2,4,8,16] [--tus-list 1,2,4,8,16,32] [--nocache-csv CSV]

The cache figures of Collinson & Sinnen 2017 for one scene (`make paper-caches` runs it per scene):
  DIR/fig11_miss_rate.csv, .png        node-cache miss rate vs size 256..8192 for dm, bf, LRP0..6 (+ the other
                                       rows of `CacheSim --sweep-out`), at --mppl, one TU          (Fig 11)
  DIR/fig8_9_bytes_per_ray.csv, .png   DRAM bytes per ray vs MPPL: no cache (Fig 4), node cache 8192 DM (Fig 8),
                                       node 4096 DM + primitive 4096 DM (Fig 9)
  DIR/cachesim.jsonl                   the JSON result line of every CacheSim run above
  DIR/tus_sweep.csv, fig12_13_tus.png  rays/s and memory utilisation vs TUs of the RTL with the 2^13-entry DM
                                       node cache (Figs 12-13); only when --tus-list is not empty; the PNG also
                                       shows --nocache-csv (make paper-nocache) when that file exists

--java is a shell command prefix that starts the JVM on the rtaccel classpath (the Makefile passes its $(JAVA);
default: $RTACCEL_JAVA). Every file is written atomically once its figure is complete; every CSV starts with a
`# scene=... config=... rtaccel=<version>` line. Bad input: one `error:` line, exit status 2, nothing written.
An entry point whose own check fails (status 3, JSON line with "ok": false) stops the driver with one `error:`
line naming its "failures" and exit status 3; the figure it was for is not written. A JVM crash: status 1.
"""
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time

from scenes.cli import EXIT_CHECK_FAILED, ArgParser, run
from scenes.errors import UserError

from ..common import NoJsonResult, failures_text, last_json as parse_last_json, provenance_line, write_text
from ..plots import caches as plot_caches, tus as plot_tus

# The paper's cache sizes (Sections 6.3 and 8): the largest node cache of its FPGA, and the split into half
# that node cache plus a primitive cache of the same storage (entries counted in primitives, lines = 4096/MPPL).
NODE_ONLY = ["--node-cache", "8192", "--node-policy", "dm"]
NODE_PRIM = ["--node-cache", "4096", "--node-policy", "dm", "--prim-cache", "4096", "--prim-policy", "dm"]
TUS_CACHE = ["--node-cache", "8192", "--node-policy", "dm"]
TUS_CACHE_DESC = "8192x1-dm"  # how SweepTus names TUS_CACHE in its provenance line (SweepTus.desc)


class JavaFailed(Exception):
    """The JVM crashed or broke its output contract: not the user's input, so exit status 1, not 2."""


class JavaCheckFailed(Exception):
    """The entry point ran but one of its own checks failed (status 3): its numbers are not a result to plot."""


def log(msg):
    print(f"[paper-caches] {msg}", file=sys.stderr, flush=True)


def int_list(text, what, ok, rule):
    """Comma-separated integers, each passing `ok`; an empty text is an empty list."""
    out = []
    for s in (t.strip() for t in text.split(",") if t.strip()):
        try:
            v = int(s)
        except ValueError:
            raise UserError(f"{what} must be comma-separated integers (got '{s}')")
        if not ok(v):
            raise UserError(f"{what}: {v} is not allowed; {rule}")
        out.append(v)
    if len(set(out)) != len(out):
        raise UserError(f"{what} lists a value twice ({text})")
    return out


def check_npy(path, what):
    try:
        with open(path, "rb") as f:
            magic = f.read(6)
    except OSError:
        raise UserError(f"{what} {path} does not exist")
    if magic != b"\x93NUMPY":
        raise UserError(f"{what} {path} is not a .npy file")


def run_java(java, main, args, what):
    """stdout of `rtaccel.cli.<main> args`. Java's `[..]` progress lines are passed on to our stderr."""
    cmd = f"{java} rtaccel.cli.{main} " + " ".join(shlex.quote(str(a)) for a in args)
    tail, crash = [], None
    # stdout to a file, not a pipe, so a chatty JVM cannot block while we read its stderr.
    with tempfile.TemporaryFile("w+") as so:
        p = subprocess.Popen(["bash", "-c", cmd], stdout=so, stderr=subprocess.PIPE, text=True)
        for line in p.stderr:
            if line.startswith("["):
                sys.stderr.write("    " + line)
            tail = (tail + [line.rstrip()])[-40:]
            if crash is None and ("Exception" in line or "Error" in line):
                crash = line.strip()  # the first one names the cause; a long trace would push it out of `tail`
        rc = p.wait()
        so.seek(0)
        out = so.read()
    if rc == 0:
        return out
    if rc == EXIT_CHECK_FAILED:
        try:
            j = parse_last_json(out)
        except NoJsonResult as e:
            raise JavaFailed(f"{what}: rtaccel.cli.{main} exited with status 3 (check failed) but {e}")
        if j.get("ok") is not False:
            raise JavaFailed(f"{what}: rtaccel.cli.{main} exited with status 3 (check failed) but its JSON line "
                             f"does not say \"ok\": false")
        raise JavaCheckFailed(f"{what}: rtaccel.cli.{main} check failed: {failures_text(j)}")
    errs = [t for t in tail if t.startswith("error:")]
    if rc == 2 and errs:  # the entry point refused its input: the same kind of failure as ours
        raise UserError(f"{what}: {errs[-1][len('error:'):].strip()}")
    cause = crash or (tail[-1].strip() if tail else "no output")
    raise JavaFailed(f"{what}: rtaccel.cli.{main} exited with status {rc}: {cause}")


def last_json(out, what):
    try:
        return parse_last_json(out)
    except NoJsonResult:
        raise JavaFailed(f"{what}: no JSON result line on stdout")


def golden_desc(rays):
    """`golden=WxH depth=D seed=S` from the meta.json that make golden writes beside rays.npy, if there is one."""
    try:
        with open(os.path.join(os.path.dirname(os.path.abspath(rays)), "meta.json")) as f:
            p = json.load(f)["params"]
        return f" golden={p['width']}x{p['height']} depth={p['depth']} seed={p['seed']}"
    except (OSError, ValueError, KeyError, TypeError):
        return ""


class Scene:
    def __init__(self, a):
        self.a = a
        self.base = ["--tris", a.tris, "--scene-label", a.scene, "--rays", a.rays, "--config", a.config, "--m", a.m,
                     "--tus", "1"]  # Figs 8, 9, 11 are one TU's access stream
        self.runs = []  # every CacheSim JSON, for cachesim.jsonl
        self.name = os.path.splitext(os.path.basename(a.scene))[0]

    def cachesim(self, mppl, extra, what):
        t0 = time.time()
        j = last_json(run_java(self.a.java, "CacheSim", self.base + ["--mppl", mppl] + extra, what), what)
        self.runs.append(j)
        rates = "".join(f", {c} miss rate {j[c + '_cache']['miss_rate']:.4f}" for c in ("node", "prim") if j[c + "_cache"]["entries"])
        log(f"{self.name}: {what}: {j['dram_bytes_per_ray']:.1f} DRAM B/ray{rates} ({time.time() - t0:.1f} s)")
        return j

    def prov(self, j, rest, version=None):
        """The first line of every CSV: what made it (scene, rays, config, version) and how."""
        return provenance_line(self.a.scene, j["config"], version or j["rtaccel"],
                               scene_fields=f"rays={j['rays']}{golden_desc(self.a.rays)}", fields=f"M={j['m']} {rest}")

    def fig11(self):
        out = self.a.out
        fd, tmp = tempfile.mkstemp(prefix=".tmp-sweep-", suffix=".csv", dir=out)
        os.close(fd)
        try:
            j = self.cachesim(self.a.mppl, ["--sweep-out", tmp], f"Fig 11 sweep, MPPL={self.a.mppl}")
            with open(tmp) as f:
                body = f.read()
        finally:
            os.unlink(tmp)
        text = self.prov(j, f"MPPL={j['mppl']} nodes={j['nodes']} tus={j['tus']} figure=11 cache=node miss_rate") + body
        plot_caches.read_fig11("CacheSim sweep", text)  # refuse a malformed sweep before it becomes an output
        write_text(os.path.join(out, "fig11_miss_rate.csv"), text)
        plot_caches.main(["fig11", os.path.join(out, "fig11_miss_rate.png"), os.path.join(out, "fig11_miss_rate.csv")])

    def fig8_9(self):
        rows, node_runs = [], []
        for mppl in self.a.mppl_list:
            node = self.cachesim(mppl, NODE_ONLY, f"Fig 8, MPPL={mppl}, node 8192 DM")
            both = self.cachesim(mppl, NODE_PRIM, f"Fig 9, MPPL={mppl}, node 4096 DM + prim 4096 DM")
            node_runs.append(node)
            # No cache = the same traversal's accesses, all from DRAM: CacheSim reports them as *_nocache.
            nb, pb = node["node_bytes_per_ray_nocache"], node["prim_bytes_per_ray_nocache"]
            rows.append(f"{mppl},nocache,{nb:.3f},{pb:.3f},{nb + pb:.3f},,")
            for v, j in (("node", node), ("node_prim", both)):
                pm = f"{j['prim_cache']['miss_rate']:.5f}" if j["prim_cache"]["entries"] else ""
                rows.append(f"{mppl},{v},{j['node_bytes_per_ray']:.3f},{j['prim_bytes_per_ray']:.3f},"
                            f"{j['dram_bytes_per_ray']:.3f},{j['node_cache']['miss_rate']:.5f},{pm}")
        # Normally one version; more only if the classpath was rebuilt mid-run, and then the CSV says so.
        versions = ",".join(sorted({j["rtaccel"] for j in self.runs}))
        nodes = ",".join(f"{j['mppl']}:{j['nodes']}" for j in node_runs)  # the tree changes with MPPL
        text = (self.prov(node_runs[0], f"nodes_by_mppl={nodes} tus=1 figures=4,8,9 node=8192x1-dm node_prim=4096x1-dm+4096x1-dm",
                          versions)
                + "# variants: nocache = *_nocache of the node run; node = --node-cache 8192 DM; node_prim = "
                  "--node-cache 4096 DM --prim-cache 4096 DM (primitives; lines = 4096/MPPL); miss rate empty = no cache\n"
                + ",".join(plot_caches.BYTES_COLUMNS) + "\n" + "\n".join(rows) + "\n")
        plot_caches.read_bytes("fig 8-9 table", text)
        out = self.a.out
        write_text(os.path.join(out, "fig8_9_bytes_per_ray.csv"), text)
        write_text(os.path.join(out, "cachesim.jsonl"), "".join(json.dumps(j) + "\n" for j in self.runs))
        plot_caches.main(["bytes", os.path.join(out, "fig8_9_bytes_per_ray.png"),
                          os.path.join(out, "fig8_9_bytes_per_ray.csv")])

    def tus(self):
        a = self.a
        t0 = time.time()
        log(f"{self.name}: Figs 12-13: RTL with the {TUS_CACHE_DESC} node cache, TUs {','.join(map(str, a.tus_list))} (slow)")
        # SweepTus writes OUT/tus_sweep.csv itself (atomically), so it goes to a scratch dir first and is only
        # moved into place once checked.
        with tempfile.TemporaryDirectory(prefix=".tmp-tus-", dir=a.out) as d:
            run_java(a.java, "SweepTus", ["--tris", a.tris, "--scene-label", a.scene, "--rays", a.tus_rays or a.rays, "--out", d,
                                          "--config", a.tus_config, "--m", a.m, "--mppl", a.mppl,
                                          "--tus-list", ",".join(map(str, a.tus_list))] + TUS_CACHE, "Figs 12-13 sweep")
            csv = os.path.join(d, "tus_sweep.csv")
            with open(csv) as f:
                head = f.readline()
            # An entry point built before the RTL cache ignores --node-cache: refuse its uncached numbers.
            if f"node_cache={TUS_CACHE_DESC}" not in head.split():
                raise JavaFailed(f"SweepTus did not simulate the {TUS_CACHE_DESC} node cache (its CSV says: "
                                 f"{head.strip()}); rebuild the classpath with the RTL cache")
            os.replace(csv, os.path.join(a.out, "tus_sweep.csv"))
        csvs = [os.path.join(a.out, "tus_sweep.csv")] + ([a.nocache_csv] if a.nocache_csv and os.path.isfile(a.nocache_csv) else [])
        plot_tus.main(os.path.join(a.out, "fig12_13_tus.png"), *csvs)
        log(f"{self.name}: Figs 12-13 done ({time.time() - t0:.0f} s)")


def main(argv=None):
    ap = ArgParser(prog="python -m dse.paper.caches", description="Paper Figs 8, 9, 11 (cache model) and 12-13 (RTL).")
    ap.add_argument("--scene", required=True, help="mesh path, used as the label in every output")
    ap.add_argument("--tris", required=True, help="tris.npy of the mesh (tools/tris)")
    ap.add_argument("--rays", required=True, help="rays.npy (make golden)")
    ap.add_argument("--tus-rays", default="", help="rays.npy of the RTL sweep (default --rays; the RTL is ~1e5x slower than the model)")
    ap.add_argument("--out", required=True, help="output directory (its parent must exist)")
    ap.add_argument("--java", default=os.environ.get("RTACCEL_JAVA", ""), help="JVM command prefix (default $RTACCEL_JAVA)")
    ap.add_argument("--config", default="fit", help="model configuration for the cache model runs (default fit)")
    ap.add_argument("--tus-config", default="paper2017", help="configuration of the RTL sweep (default paper2017, as paper-nocache)")
    ap.add_argument("--m", default="4", help="MBVH width (2, 4, 8)")
    ap.add_argument("--mppl", default="4", help="MPPL of the Fig 11 sweep and the TU sweep (default 4)")
    ap.add_argument("--mppl-list", default="1,2,4,8,16", help="MPPL values of Figs 8-9")
    ap.add_argument("--tus-list", default="", help="TU counts of Figs 12-13; empty (default) skips the RTL step")
    ap.add_argument("--nocache-csv", default="", help="uncached tus_sweep.csv to draw beside the cached one, if it exists")
    a = ap.parse_args(argv)
    # Everything is checked before the first JVM starts: a typo must not cost minutes of simulation.
    if not a.java.strip():
        raise UserError("no JVM command: give --java '<java ... -cp ...>' or set RTACCEL_JAVA (make paper-caches does)")
    if a.m not in ("2", "4", "8"):
        raise UserError(f"--m must be 2, 4 or 8 (got {a.m})")
    pow2 = (lambda v: 1 <= v <= 4096 and v & (v - 1) == 0, "MPPL must be a power of two in 1..4096 (the 4096-primitive cache has 4096/MPPL lines)")
    a.mppl_list = int_list(a.mppl_list, "--mppl-list", *pow2)
    if not a.mppl_list:
        raise UserError("--mppl-list is empty; give e.g. 1,2,4,8,16")
    a.mppl = str((int_list(a.mppl, "--mppl", *pow2) or [4])[0])
    a.tus_list = int_list(a.tus_list, "--tus-list (PAPER_TUS)", lambda v: 1 <= v <= 1024, "TU counts must be in 1..1024")
    check_npy(a.tris, "--tris")
    check_npy(a.rays, "--rays")
    if a.tus_rays:
        check_npy(a.tus_rays, "--tus-rays")
    parent = os.path.dirname(os.path.abspath(a.out))
    if not os.path.isdir(parent):
        raise UserError(f"parent directory {parent} of --out does not exist")
    os.makedirs(a.out, exist_ok=True)
    t0 = time.time()
    s = Scene(a)
    name = s.name
    try:
        log(f"{name}: Fig 11 (miss rate vs node cache size), then Figs 8-9 ({len(a.mppl_list)} MPPL x 2 cache runs)")
        s.fig11()
        s.fig8_9()
        if a.tus_list:
            s.tus()
        else:
            log(f"{name}: Figs 12-13 skipped (empty --tus-list / PAPER_TUS)")
    except JavaFailed as e:
        print(f"error: {name}: {e}", file=sys.stderr)
        return 1
    except JavaCheckFailed as e:
        print(f"error: {name}: {e}", file=sys.stderr)
        return EXIT_CHECK_FAILED
    log(f"{name}: done in {time.time() - t0:.0f} s; outputs in {a.out}")
    return 0


if __name__ == "__main__":
    run(main)

"""python -m dse.studies.bench_table NAME MODEL_JSON EMBREE_JSON — side-by-side figures of one `make bench` run."""
import json
import sys

from ..common import NoJsonResult, last_json_file


def result(path):
    try:
        return last_json_file(path)
    except (OSError, NoJsonResult) as e:
        raise SystemExit(f"error: {path}: no JSON result line ({e}); rerun make bench")


def main(name, model_path, embree_path):
    m, e = result(model_path), result(embree_path)
    assert m["rays"] == e["rays"], "model and Embree must be timed on the same rays"
    mr, er = m["model_rays_per_s_median"], e["embree_rays_per_s_median"]
    mb, eb = m["model_build_s_median"], e["embree_build_s_median"]
    mc, ec = m.get("model_rays_per_cpu_s_median"), e.get("embree_rays_per_cpu_s_median")
    print(f"[bench] {name}: {m['triangles']} triangles, {m['rays']} rays, medians of {m['repeat']} runs, "
          f"model {m['threads']} thread / Embree {e['threads']} thread(s)")
    print(f"  trace  model {mr:12.0f} rays/s   Embree {er:12.0f} rays/s   Embree/model {er / mr:6.1f}x")
    if mc and ec:
        print(f"  trace  model {mc:12.0f} rays/cpu-s Embree {ec:12.0f} rays/cpu-s Embree/model {ec / mc:6.1f}x   "
              f"(per second of the tracing thread's CPU time)")
    print(f"  build  model {mb:12.3f} s        Embree {eb:12.3f} s        model/Embree {mb / eb:6.1f}x")
    print(json.dumps({"scene": name, "rays": m["rays"], "model_rays_per_s": mr, "embree_rays_per_s": er,
                      "model_build_s": mb, "embree_build_s": eb, "model_rays_per_cpu_s": mc, "embree_rays_per_cpu_s": ec}))


if __name__ == "__main__":
    main(*sys.argv[1:4])

"""The arguments each rung's run gets (dse/explore/rungs.py)."""
from dse.explore import rungs


def config_of(args):
    return args[args.index("--config") + 1]


def test_cost_rungs_price_fit_on_the_preset_whose_refs_the_node_policy_needs():
    cases = [({"NODE_POLICY": "lrp", "NODE_CACHE": 2048}, "paper2017-lrp"),
             ({"NODE_POLICY": "hybrid"}, "paper2017-lrp"),  # the preset's 8192 entries
             ({"NODE_POLICY": "lrp", "NODE_CACHE": 0}, "paper2017"),  # no node cache: no level field needed
             ({"NODE_POLICY": "dm", "NODE_CACHE": 2048}, "paper2017"), ({}, "paper2017"),
             ({"CONFIG": "small", "NODE_POLICY": "lrp"}, "small")]  # a preset given is kept
    for fid in rungs.COST_RUNGS:
        for cfg, want in cases:
            cmd, args = rungs.task_args(fid, {"CONFIG": "fit", **cfg}, None, "out", "xc7a100t")
            assert cmd == "area" and config_of(args) == want, (fid, cfg, args)

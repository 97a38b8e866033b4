"""The numbers of Collinson & Sinnen 2017 that `make paper` sets ours beside, each with where it is printed.

Only what the paper's text and tables state; where a figure is a plot without printed values, the shape the
text describes is kept instead (SHAPES).
"""

PAPER = "Collinson & Sinnen 2017"
SCENES = ("Kitchen", "Classroom", "Hairball", "Sponza")
CLOSED = ("Kitchen", "Classroom", "Sponza")  # the paper groups Sponza with the closed scenes in Sections 5-8

# Table 1 (Section 5.1): QBVH, MPPL 4.
TABLE1 = {"Kitchen": (86032, 26381, 15), "Classroom": (247000, 80356, 15), "Hairball": (2880000, 996000, 17),
          "Sponza": (66450, 22585, 12)}  # primitives, nodes, max tree depth

# Section 5.3 (Figs 5-6): caching every node down to level 4 (at most 341 QBVH nodes) = this share of all nodes
# and of all node accesses.
TOP_LEVELS = 5  # levels 0..4
TOP_SHARE = {"Kitchen": (0.013, 0.62), "Classroom": (0.008, 0.73), "Sponza": (0.030, 0.68), "Hairball": (0.0007, 0.19)}

# Section 6.3 (Fig 8): the 2^13-entry DM node cache cuts node bandwidth per ray by up to this factor.
NODE_CACHE_CUT = {"Kitchen": 75, "Classroom": 50, "Sponza": 28, "Hairball": 3.7}

# Section 4 / 8: the board.
CLOCK_MHZ = 150
FPGA_GBPS = 1.2       # DDR2 peak (Section 9); ~50 % sustained in practice (Section 8)
CPU_GBPS = 25.6       # dual-channel DDR3-1600 of the i5-3470 (Section 9)
GPU_GBPS = 12.8       # Radeon HD 5450 (Section 9)
TABLE2_TUS = 32

# Table 2 (Section 9): rays/s. CPU = LuxRender QBVH, SSE, four threads on an i5-3470; GPU = OpenCL QBVH.
TABLE2 = {
    "CPU": {"Kitchen": 8.7e5, "Classroom": 1.1e6, "Hairball": 3.31e5, "Sponza": 7.64e5},
    "GPU": {"Kitchen": 2.54e5, "Classroom": 2.86e5, "Hairball": 6.54e4, "Sponza": 2.65e5},
    "FPGA": {"Kitchen": 2.6e5, "Classroom": 2.52e5, "Hairball": 1.23e5, "Sponza": 3.04e5},
}
# Section 9 (Fig 15): FPGA over CPU in rays/s per GB/s, as the text states it.
FIG15_TEXT = {"Kitchen": "over 6x", "Classroom": "5x", "Hairball": "nearly 8x", "Sponza": "over 8x"}


def per_gbps(platform, scene):
    """Table 2's rays/s over the platform's available bandwidth (how Fig 15 is made)."""
    gbps = {"CPU": CPU_GBPS, "GPU": GPU_GBPS, "FPGA": FPGA_GBPS}[platform]
    return TABLE2[platform][scene] / gbps


def fig15_ratio(scene):
    """FPGA / CPU in rays/s per GB/s, from Table 2 and Section 9's bandwidths."""
    return per_gbps("FPGA", scene) / per_gbps("CPU", scene)


SHAPES = {
    "fig4": "node bandwidth about an order of magnitude above primitive bandwidth on Kitchen, Classroom and Sponza, "
            "1.5-3x on Hairball; raising MPPL lowers node and raises primitive bytes; the total is flat on the closed "
            "scenes with MPPL 2 slightly lowest, while Hairball favours MPPL >= 4 (Section 5.2)",
    "fig5_6": "nodes per level rise to a peak just past half depth; accesses per level peak earlier than nodes; "
              "accesses per node fall with depth (Section 5.3)",
    "fig8": "the node cache cuts node bytes by over an order of magnitude on the closed scenes at every MPPL "
            "(up to 75x Kitchen, 50x Classroom, 28x Sponza) and up to 3.7x on Hairball; primitive bytes then "
            "dominate (Section 6.3)",
    "fig9": "halving the node cache for a 4096-primitive cache lowers the total on Kitchen, Classroom and Sponza "
            "and raises it slightly on Hairball (Section 6.3)",
    "fig11": "LRP misses less than direct-mapped at small sizes, LRP6 best; the advantage disappears at large sizes; "
             "the breadth-first buffer is worse on Hairball (Section 7.3)",
    "fig12_13": "without cache more TUs give no speed-up and utilisation stays not far above 50 %; with the 2^13 DM "
                "node cache rays/s rise with TUs on Kitchen, Classroom and Sponza at lower utilisation, while "
                "Hairball stops scaling after 16 TUs (Section 8)",
}


def counterpart(scene_name):
    """The paper scene(s) a mesh of ours stands for: sponza for Sponza, a procedural hairball for Hairball, any
    other (closed, camera inside) scene for Kitchen and Classroom."""
    n = scene_name.lower()
    if "sponza" in n:
        return ("Sponza",)
    if "hairball" in n:
        return ("Hairball",)
    return ("Kitchen", "Classroom")

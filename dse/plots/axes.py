"""Axis conventions shared by the DSE plots."""


def log2_x(ax, ticks, xlabel, ylabel):
    """Power-of-two sweep axis (cache sizes, MPPL, TUs): log2 x with a tick per point, y from zero, light grid."""
    ax.set_xscale("log", base=2)
    ax.set_xticks(ticks)
    ax.set_xticklabels([f"{v:g}" for v in ticks])
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)

"""Plots of simulation results (matplotlib, no display needed)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..parameters import paper  # noqa: E402


def plot_simulation(res, path: Path, title: str) -> None:
    """Segment angle and rate; root force and torque of the whole tail."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    ax = axes[0]
    ax.plot(res.time_s * 1000, res.segment_angle_deg, color="tab:orange")
    ax.axhline(38.0, color="grey", lw=0.8, ls="--", label="38 deg window")
    ax.set(xlabel="time [ms]", ylabel="segment bending angle [deg]", title="one segment, extension")
    ax.legend(loc="lower right")
    ax = axes[1]
    ax.plot(res.time_s * 1000, res.segment_rate_deg_s, color="tab:red", label="simulated")
    ax.axhline(paper.SEGMENT_PEAK_VELOCITY_EXTENSION.value, color="k", lw=0.8, ls=":",
               label=f"paper at 6 bar ({paper.SEGMENT_PEAK_VELOCITY_EXTENSION.value} deg/s)")
    ax.set(xlabel="time [ms]", ylabel="angular velocity [deg/s]",
           title=f"peak {res.peak_velocity_deg_s:.0f} deg/s up to 38 deg")
    ax.legend(loc="upper right")
    ax = axes[2]
    ax.plot(res.tail_time_s * 1000, (res.root_force_n ** 2).sum(1) ** 0.5, label="|force| [N]")
    ax.plot(res.tail_time_s * 1000, (res.root_torque_nm ** 2).sum(1) ** 0.5, label="|torque| [N m]")
    ax.set(xlabel="time [ms]", title=f"whole tail at the root, payload {res.payload_g:g} g")
    ax.legend(loc="upper right")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

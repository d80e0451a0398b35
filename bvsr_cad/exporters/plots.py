"""Plots of the analyses and simulation results (matplotlib, no display needed)."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..models.dynamics import VELOCITY_WINDOW_DEG  # noqa: E402
from ..parameters import paper  # noqa: E402


def plot_workspace(ws, path, title: str) -> None:
    """The tip cloud in the XY, XZ and YZ planes (PNG)."""
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.4))
    for ax, (i, j) in zip(axes, ((0, 1), (0, 2), (1, 2))):
        ax.scatter(ws.tip_mm[:, i], ws.tip_mm[:, j], s=1, alpha=0.3)
        ax.set_xlabel(f"{'xyz'[i]} (mm)")
        ax.set_ylabel(f"{'xyz'[j]} (mm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, lw=0.3)
    fig.suptitle(f"{title}: tip workspace, {ws.samples} samples (tail horizontal, gravity -Y)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_clearance_map(
    th: np.ndarray,
    ph: np.ndarray,
    bound: np.ndarray,
    path,
    title: str,
    workspace_theta_rad: float,
    min_clearance_mm: float,
    curves: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
) -> None:
    """The map, the required clearance as a red contour and optional (phi, theta) curves (rad)."""
    fig, ax = plt.subplots(figsize=(7, 4.6))
    cs = ax.pcolormesh(np.degrees(ph), np.degrees(th), bound, shading="auto", cmap="viridis")
    fig.colorbar(cs, label="clearance lower bound (mm)")
    ax.contour(np.degrees(ph), np.degrees(th), bound, levels=[min_clearance_mm], colors="r")
    ax.plot([], [], color="r", label=f"clearance bound = {min_clearance_mm:g} mm (required)")
    for (label, (cp, ct)), style in zip((curves or {}).items(), ("w-", "m:", "c-.")):
        order = np.argsort(cp)
        ax.plot(
            np.degrees(np.asarray(cp)[order]),
            np.degrees(np.asarray(ct)[order]),
            style,
            lw=1.5,
            label=label,
        )
    ax.axhline(
        np.degrees(workspace_theta_rad),
        color="w",
        ls="--",
        lw=1,
        label="largest theta in the workspace",
    )
    ax.set_xlabel("phi (deg)")
    ax.set_ylabel("theta (deg)")
    ax.set_title(title)
    ax.set_ylim(0, np.degrees(th.max()) * 1.12)
    ax.legend(loc="lower left", fontsize=8, framealpha=0.85)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_simulation(res, path: Path, title: str) -> None:
    """Segment angle and rate; root force and torque of the whole tail."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    ax = axes[0]
    ax.plot(res.time_s * 1000, res.segment_angle_deg, color="tab:orange")
    ax.axhline(
        VELOCITY_WINDOW_DEG,
        color="grey",
        lw=0.8,
        ls="--",
        label=f"{VELOCITY_WINDOW_DEG:g} deg window",
    )
    ax.set(xlabel="time [ms]", ylabel="segment bending angle [deg]", title="one segment, extension")
    ax.legend(loc="lower right")
    ax = axes[1]
    ax.plot(res.time_s * 1000, res.segment_rate_deg_s, color="tab:red", label="simulated")
    ax.axhline(
        paper.SEGMENT_PEAK_VELOCITY_EXTENSION.value,
        color="k",
        lw=0.8,
        ls=":",
        label=f"paper at 6 bar ({paper.SEGMENT_PEAK_VELOCITY_EXTENSION.value} deg/s)",
    )
    ax.set(
        xlabel="time [ms]",
        ylabel="angular velocity [deg/s]",
        title=f"peak {res.peak_velocity_deg_s:.0f} deg/s up to 38 deg",
    )
    ax.legend(loc="upper right")
    ax = axes[2]
    ax.plot(res.tail_time_s * 1000, (res.root_force_n**2).sum(1) ** 0.5, label="|force| [N]")
    ax.plot(res.tail_time_s * 1000, (res.root_torque_nm**2).sum(1) ** 0.5, label="|torque| [N m]")
    ax.set(xlabel="time [ms]", title=f"whole tail at the root, payload {res.payload_g:g} g")
    ax.legend(loc="upper right")
    fig.suptitle(title)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_measurements(rows: list[dict], path: Path, title: str, band_rel: float) -> None:
    """Predicted against reported, one point per data row (|value|, log-log: the rows span
    exponents to newtons per metre), the tables' values hollow, the fitted ones filled, fit rows
    blue and holdout rows orange; the grey band is +/- ``band_rel``."""
    fig, ax = plt.subplots(figsize=(7.2, 6.4))
    values = [
        abs(v)
        for r in rows
        for v in (r["reported"], r["uncalibrated"], r["calibrated"])
        if np.isfinite(v) and v != 0
    ]
    lo, hi = min(values) / 2, max(values) * 2
    line = np.geomspace(lo, hi, 50)
    ax.fill_between(
        line,
        line * (1 - band_rel),
        line * (1 + band_rel),
        color="0.85",
        label=f"within +/-{100 * band_rel:.0f} %",
    )
    ax.plot(line, line, color="0.4", lw=0.8)
    for role, color in (("fit", "tab:blue"), ("holdout", "tab:orange")):
        for r in (r for r in rows if r["role"] == role):
            x, u, c = abs(r["reported"]), abs(r["uncalibrated"]), abs(r["calibrated"])
            if np.isfinite(u) and np.isfinite(c) and u > 0 and c > 0:
                ax.plot([x, x], [u, c], color=color, lw=0.6, alpha=0.6)
            if np.isfinite(u) and u > 0:
                ax.scatter([x], [u], facecolors="none", edgecolors=color, s=28)
            if np.isfinite(c) and c > 0:
                ax.scatter([x], [c], color=color, s=28)
                ax.annotate(
                    str(r["row"]), (x, c), fontsize=7, xytext=(3, 2), textcoords="offset points"
                )
    ax.scatter([], [], color="tab:blue", s=28, label="fit row, calibrated")
    ax.scatter([], [], color="tab:orange", s=28, label="holdout row, calibrated")
    ax.scatter(
        [], [], facecolors="none", edgecolors="0.3", s=28, label="uncalibrated (tables' values)"
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_xlabel("reported |value| (each row in its own unit)")
    ax.set_ylabel("predicted |value|")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", lw=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_cart(runs, path: Path, title: str) -> None:
    """The cart's pitch (front lift) and yaw over time, one panel per motion."""
    fig, axes = plt.subplots(1, len(runs), figsize=(6 * len(runs), 4), squeeze=False)
    for ax, r in zip(axes[0], runs):
        ax.plot(r.time_s * 1000, r.pitch_deg, label="pitch (front up +)")
        ax.plot(r.time_s * 1000, r.yaw_deg, label="yaw")
        ax.set_title(f"{r.motion}: peak {r.peak_angle_deg:.2f} deg")
        ax.set_xlabel("time (ms)")
        ax.set_ylabel("cart angle (deg)")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_quadruped_impact(runs, path: Path, title: str) -> None:
    """Fig. 17(d)'s shape: per ball (columns), the tail tip's and the torso's speed, soft against
    rigid, and the root force, over the time from the first touch."""
    balls = list(dict.fromkeys(r.ball for r in runs))
    fig, axes = plt.subplots(3, len(balls), figsize=(5.5 * len(balls), 8.5), squeeze=False)
    styles = {"soft": ("C0", "BVSR (soft)"), "rigid": ("C3", "rigid PLA twin")}
    for col, ball in enumerate(balls):
        for r in (r for r in runs if r.ball == ball):
            color, label = styles.get(r.tail, ("k", r.tail))
            t_ms = r.time_s * 1000
            axes[0, col].plot(t_ms, r.tip_speed_m_s, color=color, label=label)
            axes[1, col].plot(
                t_ms,
                np.linalg.norm(r.torso_velocity_m_s, axis=1),
                color=color,
                label=f"{label}: peak {r.peak_torso_speed_m_s:.3f} m/s",
            )
            axes[2, col].plot(
                t_ms,
                np.linalg.norm(r.root_force_n, axis=1),
                color=color,
                lw=0.8,
                label=f"{label}: peak {r.peak_root_force_n:.0f} N (1 ms mean)",
            )
        axes[0, col].set_title(ball)
        for row, ylabel in enumerate(
            ("tail tip speed (m/s)", "torso velocity change (m/s)", "root force change (N)")
        ):
            ax = axes[row, col]
            ax.set_ylabel(ylabel)
            ax.grid(True, lw=0.3)
            ax.legend(fontsize=7)
        axes[2, col].set_xlabel("time from first touch (ms)")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_quadruped_payload(runs, path: Path, title: str) -> None:
    """Fig. 18's shape: per payload (columns), the tip's travel, the torso's roll, pitch and yaw
    changes and the root's force and torque changes over the waggle, extension and flexion."""
    fig, axes = plt.subplots(3, len(runs), figsize=(4.2 * len(runs), 8.5), squeeze=False)
    for col, r in enumerate(runs):
        t = r.time_s
        axes[0, col].plot(t, r.tip_distance_mm, color="k")
        axes[0, col].set_title(f"{r.payload_g:g} g on the tip")
        for k, name in enumerate(("roll", "pitch", "yaw")):
            axes[1, col].plot(t, r.attitude_deg[:, k], label=name)
        axes[2, col].plot(t, np.linalg.norm(r.root_force_n, axis=1), "C0", label="force (N)")
        axes[2, col].plot(t, np.linalg.norm(r.root_torque_nm, axis=1), "C1", label="torque (N m)")
        for row, ylabel in enumerate(
            ("tip travel (mm)", "torso angle change (deg)", "root force, torque change")
        ):
            axes[row, col].grid(True, lw=0.3)
            if col == 0:
                axes[row, col].set_ylabel(ylabel)
        axes[1, col].legend(fontsize=7)
        axes[2, col].legend(fontsize=7)
        axes[2, col].set_xlabel("time (s): waggle, extension, flexion")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

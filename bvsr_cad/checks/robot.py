"""Checks on the robot descriptions of an export, in real simulators.

Everything here reads files: the manifest's ``robot`` section, the URDF, the
MJCF scenes and the meshes. Nothing is clamped or balanced: a failing check
names the link or the file and by how much.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import trimesh

from .. import units
from ..extras import missing, skipped_note
from ..models.kinematics import (
    TailKinematics,
    chord_length_mm,
    joint_transform_mount,
    joint_transform_prb,
    mount_angles,
    mount_order,
    prb_angles,
    uv_from_theta_phi,
)
from ..parameters.load import load_spec
from .export import Export
from .result import CheckResult

MASS_TOLERANCE = 0.001  # robot mass vs the manifest's tail mass
INERTIA_TOLERANCE = 0.01  # link inertia vs an independent computation from its meshes
FK_TOLERANCE_M = 1e-6
FK_POSES = 200
#: 1 s after release under gravity the sag has died down: the largest hinge speed of a file whose
#: joints each bend on two pivots (the URDF's, the exact, reduced and per-segment chains; BVSR_L's
#: exact chain 0.08 rad/s).
SETTLE_QVEL_RAD_S = 0.1
#: The files whose joints bend on one pivot, each hinge turning through the whole bend (the mount
#: variant's universal joints): the same bend rate is twice the hinge speed of a two-pivot file, so
#: their limit is twice :data:`SETTLE_QVEL_RAD_S` (released under gravity, BVSR_L's mount variant
#: sags as far as its exact chain, 97 mm at the tip, at 1.9 times its hinge speeds).
ONE_PIVOT_FILES = ("mjcf_mount",)
#: Mimic / chord couplings held while stepping (rad or m). MuJoCo's equality
#: constraints are soft; released under gravity the residual stays below this.
EQUALITY_TOLERANCE = 1e-3
#: The default files' reduced chain steps at 1-2 ms, so its equalities (the two pivots of a joint,
#: the joints of a segment) are as soft as a 2-4 ms time constant: released under gravity, the
#: pivots of a joint differ by up to 7.5 mrad (0.2 mm of shear over the 24 mm middle link) in the
#: first steps.
EQUALITY_TOLERANCE_REDUCED = 1e-2
VIRTUAL_MASS_LIMIT_KG = 1e-6


def _inertia_problems(mass: float, I: np.ndarray) -> tuple[bool, str]:
    w = np.linalg.eigvalsh(I)
    a, b, c = sorted(w)
    ok = mass > 0 and a > 0 and a + b >= c * (1 - 1e-9)
    return ok, f"mass {mass:.3e} kg, principal moments {a:.3e} {b:.3e} {c:.3e} kg m2"


def _mesh_inertial(exp: Export, visuals: list[dict]) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, CoM and inertia about the CoM of a link's meshes (trimesh, SI)."""
    masses, coms, inertias = [], [], []
    for v in visuals:
        mesh = trimesh.load(exp.root / v["mesh"], force="mesh")
        mesh.density = units.g_cm3_to_kg_m3(v["density_g_cm3"])
        masses.append(mesh.mass)
        coms.append(mesh.center_mass)
        inertias.append(mesh.moment_inertia)  # about the mesh's CoM, frame axes
    m = float(sum(masses))
    c = sum(mi * ci for mi, ci in zip(masses, coms)) / m
    I = np.zeros((3, 3))
    for mi, ci, Ii in zip(masses, coms, inertias):
        d = ci - c
        I += Ii + mi * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return m, c, I


def _compose_manifest(
    entries: list[tuple[dict, np.ndarray]],
) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, CoM, inertia of manifest links placed by translations (parallel-axis theorem)."""
    m = sum(e["mass_kg"] for e, _ in entries)
    c = sum(e["mass_kg"] * (np.asarray(e["com_m"]) + off) for e, off in entries) / m
    I = np.zeros((3, 3))
    for e, off in entries:
        d = np.asarray(e["com_m"]) + off - c
        I += np.asarray(e["inertia_kg_m2"]) + e["mass_kg"] * (
            np.dot(d, d) * np.eye(3) - np.outer(d, d)
        )
    return m, c, I


def check_inertias(exp: Export) -> list[CheckResult]:
    robot = exp.manifest["robot"]
    links = {l["name"]: l for l in robot["links"]}
    out = []
    for link in robot["links"]:
        ok, text = _inertia_problems(link["mass_kg"], np.asarray(link["inertia_kg_m2"]))
        out.append(
            CheckResult(
                f"robot_inertia_valid:{link['name']}", ok, int(ok), 1, "", robot["urdf"], text
            )
        )
        if link["role"] == "virtual":
            out.append(
                CheckResult(
                    f"robot_virtual_mass:{link['name']}",
                    link["mass_kg"] < VIRTUAL_MASS_LIMIT_KG,
                    link["mass_kg"] * 1e6,
                    VIRTUAL_MASS_LIMIT_KG * 1e6,
                    "mg",
                    robot["urdf"],
                )
            )
    total_kg = sum(l["mass_kg"] for l in robot["links"])
    tail_kg = units.g_to_kg(exp.manifest["mass_g"]["tail"])
    rel = abs(total_kg - tail_kg) / tail_kg
    out.append(
        CheckResult(
            "robot_mass_matches_tail",
            rel <= MASS_TOLERANCE,
            100 * rel,
            100 * MASS_TOLERANCE,
            "%",
            robot["urdf"],
            f"links {total_kg * units.G_PER_KG:.4f} g (virtual links included), "
            f"parts {tail_kg * units.G_PER_KG:.4f} g",
        )
    )
    # Each link with meshes against its meshes; a joint's two deformable halves together at rest.
    for b in robot["bending_joints"]:
        j = b["name"]
        a, c = links[f"{j}_after_theta_a"], links[f"{j}_after_chord"]
        mine = _compose_manifest([(a, np.zeros(3)), (c, np.array([0.0, 0.0, b["arc_length_m"]]))])
        out.append(_compare(exp, f"{j}_soft(at rest)", mine, a["visuals"], robot["urdf"]))
    for link in robot["links"]:
        if link["role"] == "rigid":
            mine = (link["mass_kg"], np.asarray(link["com_m"]), np.asarray(link["inertia_kg_m2"]))
            out.append(_compare(exp, link["name"], mine, link["visuals"], robot["urdf"]))
    return out


def _compare(exp: Export, name: str, mine, visuals, where: str) -> CheckResult:
    m0, c0, I0 = mine
    m1, c1, I1 = _mesh_inertial(exp, visuals)
    # Relative differences; the CoM is judged against the body's radius of gyration.
    gyr = math.sqrt(np.trace(I1) / m1)
    err = max(
        abs(m0 - m1) / m1,
        np.linalg.norm(c0 - c1) / gyr,
        np.linalg.norm(I0 - I1) / np.linalg.norm(I1),
    )
    return CheckResult(
        f"robot_inertia_vs_mesh:{name}",
        err <= INERTIA_TOLERANCE,
        100 * err,
        100 * INERTIA_TOLERANCE,
        "%",
        where,
        f"B-rep {m0 * units.G_PER_KG:.3f} g vs meshes {m1 * units.G_PER_KG:.3f} g; largest "
        "relative "
        "difference of mass, CoM (per radius of gyration) and inertia tensor",
    )


def check_urdf_tools(exp: Export) -> list[CheckResult]:
    rel = exp.manifest["robot"]["urdf"]  # results name the file relative to the export
    urdf = exp.root / rel
    out = []
    tool = shutil.which("check_urdf")
    if tool:
        res = subprocess.run([tool, str(urdf)], capture_output=True, text=True)
        out.append(
            CheckResult(
                "urdf_check_urdf",
                res.returncode == 0,
                res.returncode,
                0,
                "exit code",
                rel,
                (res.stderr or res.stdout).strip().splitlines()[-1] if res.returncode else "",
            )
        )
    else:
        out.append(
            CheckResult(
                "urdf_check_urdf",
                None,
                None,
                0,
                "exit code",
                rel,
                "check_urdf not installed (Debian: liburdfdom-tools)",
            )
        )
    if missing("crosscheck"):
        out.append(CheckResult("urdf_yourdfpy", None, None, 1, "", rel, skipped_note("crosscheck")))
        return out
    import yourdfpy

    try:
        model = yourdfpy.URDF.load(str(urdf), build_scene_graph=True, load_meshes=False)
        ok = bool(model.validate())
        note = f"{len(model.robot.links)} links, {len(model.robot.joints)} joints"
    except Exception as exc:  # noqa: BLE001 - report what the tool said
        ok, note = False, f"{type(exc).__name__}: {exc}"
    out.append(CheckResult("urdf_yourdfpy", ok, int(ok), 1, "", rel, note))
    return out


def _equality_residual(m, d) -> float:
    worst = 0.0
    for e in range(m.neq):
        q1 = d.qpos[m.jnt_qposadr[m.eq_obj1id[e]]] - m.qpos0[m.jnt_qposadr[m.eq_obj1id[e]]]
        q2 = d.qpos[m.jnt_qposadr[m.eq_obj2id[e]]] - m.qpos0[m.jnt_qposadr[m.eq_obj2id[e]]]
        c = m.eq_data[e, :5]
        worst = max(
            worst, abs(q1 - (c[0] + c[1] * q2 + c[2] * q2**2 + c[3] * q2**3 + c[4] * q2**4))
        )
    return float(worst)


def _step(m, gravity: bool, seconds: float = 1.0, self_contacts: bool = True):
    """The compiled model ``m`` (changed here) stepped for ``seconds``."""
    import mujoco

    if not self_contacts:
        m.geom_conaffinity[:] = (
            0  # every geom keeps its contype: the MJCF's rule, the world's geoms excepted
        )
    if not gravity:
        m.opt.gravity[:] = 0.0
    d = mujoco.MjData(m)
    worst_eq = 0.0
    steps = int(round(seconds / m.opt.timestep))
    for i in range(steps):
        mujoco.mj_step(m, d)
        if i % 10 == 0:
            worst_eq = max(worst_eq, _equality_residual(m, d))
    warnings = int(sum(w.number for w in d.warning))
    at_limit = []
    for j in range(m.njnt):
        if m.jnt_limited[j]:
            q = d.qpos[m.jnt_qposadr[j]]
            lo, hi = m.jnt_range[j]
            if q <= lo + 1e-9 or q >= hi - 1e-9:
                at_limit.append(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j))
    # The reduced chains bound each joint's bend by limited fixed tendons (the hinges have no
    # range).
    for t in range(m.ntendon):
        if m.tendon_limited[t]:
            lo, hi = m.tendon_range[t]
            if d.ten_length[t] <= lo + 1e-9 or d.ten_length[t] >= hi - 1e-9:
                at_limit.append(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t))
    drift = float(np.max(np.abs(d.qpos - m.qpos0))) if m.nq else 0.0
    return m, d, warnings, worst_eq, at_limit, drift


@contextlib.contextmanager
def _quiet_cwd(path: Path):
    """MuJoCo writes MUJOCO_LOG.TXT into the working folder on a warning: keep it out of the
    user's."""
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


#: The robot description files :func:`check_mujoco` compiles and steps, in its order.
MUJOCO_FILES = ("urdf", "mjcf", "mjcf_per_segment", "mjcf_exact", "mjcf_mount")


def check_mujoco(exp: Export, keys: tuple[str, ...] = MUJOCO_FILES) -> list[CheckResult]:
    """Each robot description file of ``keys`` (:data:`MUJOCO_FILES`) compiled and stepped for 1 s
    in MuJoCo."""
    robot = exp.manifest["robot"]
    out = []
    with _quiet_cwd(exp.root):
        for key in keys:
            rel = robot.get(key)
            if rel is not None:
                out += _check_mujoco_file(exp.root / rel, key, rel)
    return out


def _check_mujoco_file(path: Path, key: str, rel: str) -> list[CheckResult]:
    """One robot description (manifest key ``key``, export path ``rel``) compiled and stepped for
    1 s: it compiles (the URDF: and its links touch only where they should), then
    :func:`_stepped_results`."""
    # A URDF cannot carry the rod's springs, so under gravity it would fold onto its limits: it is
    # stepped without gravity and must not move at all.
    gravity = key != "urdf"
    out = []
    try:
        import mujoco

        compiled = mujoco.MjModel.from_xml_path(str(path))
        if key == "urdf":  # its contacts at rest, before it is stepped (which changes the model)
            out.append(_urdf_self_contacts(compiled, rel))
        # MuJoCo's URDF import collides every two links but a parent and its child: the exact
        # chain puts four links between neighbouring panels, whose SOA and rod halves meet (and
        # overlap by their tilt) at mid-gap in every pose. The MJCF turns the tail's self-contacts
        # off (conaffinity 0); the URDF cannot say so to MuJoCo, so it is stepped with the same
        # rule.
        stepped = _step(compiled, gravity=gravity, self_contacts=key != "urdf")
    except Exception as exc:  # noqa: BLE001 - the compiler's message is the result
        out.append(CheckResult(f"mujoco_compile:{key}", False, 0, 1, "", rel, str(exc)))
        return out
    return out + _stepped_results(key, rel, gravity, *stepped)


def _stepped_results(
    key: str, rel: str, gravity: bool, m, d, warn: int, eq: float, at_limit: list[str], drift: float
) -> list[CheckResult]:
    """What 1 s of stepping (:func:`_step`) showed: the model compiled, MuJoCo gave no warning, the
    couplings held, no joint or bend limit was reached, and :func:`_rest_result`."""
    tol = EQUALITY_TOLERANCE if key in ("urdf", "mjcf_exact") else EQUALITY_TOLERANCE_REDUCED
    return [
        CheckResult(
            f"mujoco_compile:{key}",
            True,
            1,
            1,
            "",
            rel,
            f"{m.nbody} bodies, {m.njnt} joints, {m.neq} equalities, {m.nu} actuators",
        ),
        CheckResult(
            f"mujoco_warnings_1s:{key}",
            warn == 0,
            warn,
            0,
            "warnings",
            rel,
            "1 s from rest " + ("under gravity" if gravity else "without gravity"),
        ),
        CheckResult(
            f"mujoco_couplings_held:{key}",
            eq <= tol,
            eq,
            tol,
            "rad or m",
            rel,
            "largest mimic/chord equality residual while stepping",
        ),
        CheckResult(
            f"mujoco_no_joint_at_limit:{key}",
            not at_limit,
            len(at_limit),
            0,
            "joints or bend-limit tendons",
            rel,
            ", ".join(at_limit),
        ),
        _rest_result(key, rel, gravity, d, drift),
    ]


def _rest_result(key: str, rel: str, gravity: bool, d, drift: float) -> CheckResult:
    """Without gravity the model must not have moved at all; under gravity it must have settled
    within the 1 s."""
    if not gravity:
        return CheckResult(
            f"mujoco_no_drift:{key}",
            drift <= 1e-9,
            drift,
            1e-9,
            "rad or m",
            rel,
            "largest joint displacement after 1 s at rest without gravity",
        )
    qvel = float(np.max(np.abs(d.qvel)))
    limit = SETTLE_QVEL_RAD_S * (2 if key in ONE_PIVOT_FILES else 1)
    return CheckResult(
        f"mujoco_settled_1s:{key}",
        qvel <= limit,
        qvel,
        limit,
        "rad/s or m/s",
        rel,
        "largest joint speed 1 s after release under gravity",
    )


def _urdf_self_contacts(m, rel: str) -> CheckResult:
    """MuJoCo's import of the URDF (``m``, compiled) at rest: its links touch only where
    neighbouring panels' halves of a column meet (the contacts :func:`check_mujoco` turns off); any
    other pair would be shapes that overlap."""
    import mujoco

    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    bodies = m.geom_bodyid[d.contact.geom[: d.ncon]]
    pairs = {tuple(sorted(m.body(int(b)).name for b in pair)) for pair in bodies}
    neighbours = {tuple(sorted((f"panel{k}", f"panel{k + 1}"))) for k in range(m.nbody)}
    others = sorted(f"{a}-{b}" for a, b in pairs if (a, b) not in neighbours)
    return CheckResult(
        "mujoco_self_contacts_only_neighbours:urdf",
        not others,
        len(others),
        0,
        "link pairs",
        rel,
        ", ".join(others) or f"{len(pairs)} neighbouring panel pairs touch at rest (column halves)",
    )


def _import_pybullet():
    """pybullet prints its build time on the C-level stderr when imported (noise under ``-q``)."""
    import sys

    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    saved, devnull = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    try:
        sys.stderr.flush()
        os.dup2(devnull, 2)
        import pybullet
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)
    return pybullet


def check_pybullet(exp: Export) -> list[CheckResult]:
    if missing("crosscheck"):
        return [
            CheckResult(
                "pybullet_masses",
                None,
                None,
                1e-6,
                "relative",
                exp.manifest["robot"]["urdf"],
                skipped_note("crosscheck"),
            )
        ]
    pb = _import_pybullet()

    urdf = exp.root / exp.manifest["robot"]["urdf"]
    expected = {l["name"]: l["mass_kg"] for l in exp.manifest["robot"]["links"]}
    with contextlib.redirect_stdout(io.StringIO()):
        cid = pb.connect(pb.DIRECT)
    try:
        # A fixed base would report the root's mass as 0: load it free to read every mass.
        body = pb.loadURDF(
            str(urdf), useFixedBase=False, flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid
        )
        masses = {
            pb.getBodyInfo(body, physicsClientId=cid)[0].decode(): pb.getDynamicsInfo(
                body, -1, physicsClientId=cid
            )[0]
        }
        for j in range(pb.getNumJoints(body, physicsClientId=cid)):
            name = pb.getJointInfo(body, j, physicsClientId=cid)[12].decode()
            masses[name] = pb.getDynamicsInfo(body, j, physicsClientId=cid)[0]
    finally:
        pb.disconnect(cid)
    worst = max(abs(masses.get(n, -1.0) - m) / max(m, 1e-12) for n, m in expected.items())
    return [
        CheckResult(
            "pybullet_masses",
            worst <= 1e-6,
            worst,
            1e-6,
            "relative",
            exp.manifest["robot"]["urdf"],
            f"{len(masses)} links loaded with URDF_USE_INERTIA_FROM_FILE",
        )
    ]


def check_fk(exp: Export) -> list[CheckResult]:
    """MuJoCo's forward kinematics of the MJCF files against the kinematics module at random poses:
    the exact chain's file against Eq 2, the default (reduced) file and the mount variant against
    their own closed forms (:func:`bvsr_cad.models.kinematics.joint_transform_prb`,
    :func:`~bvsr_cad.models.kinematics.joint_transform_mount`); how far those lie from Eq 2 is the
    manifest's ``chains`` entry."""

    robot = exp.manifest["robot"]
    spec = load_spec(exp.root / exp.manifest["params_file"])
    kin = TailKinematics.from_spec(spec)
    rng = np.random.default_rng(0)
    n = spec.joints
    limits = np.array([b["theta_max_rad"] for b in robot["bending_joints"]])
    theta = rng.uniform(0, 1, (FK_POSES, n)) * limits
    phi = rng.uniform(-math.pi, math.pi, (FK_POSES, n))
    _, frames = kin.frames(uv_from_theta_phi(theta, phi))
    L_mm = spec.joint.gap_mm
    tz = np.eye(4)
    tz[2, 3] = spec.joint.panel_thickness_mm

    def composed(joint) -> np.ndarray:
        """Each panel's frame, joint k's transform ``joint(k)`` after panel k-1's thickness."""
        frames = np.broadcast_to(np.eye(4), (FK_POSES, n + 1, 4, 4)).copy()
        for k in range(n):
            frames[:, k + 1] = frames[:, k] @ tz @ joint(k)
        return frames

    reduced = composed(lambda k: joint_transform_prb(theta[:, k], phi[:, k], L_mm))
    mounted = composed(
        lambda k: joint_transform_mount(theta[:, k], phi[:, k], L_mm, mount_order(k + 1))
    )
    a, b = prb_angles(theta, phi)
    hinge = [mount_angles(theta[:, k], phi[:, k], mount_order(k + 1)) for k in range(n)]

    def exact_pose(d, p, k):
        j = f"j{k + 1}"
        d.joint(f"{j}_phi").qpos = phi[p, k]
        d.joint(f"{j}_theta_a").qpos = theta[p, k] / 2
        d.joint(f"{j}_chord").qpos = units.mm_to_m(float(chord_length_mm(theta[p, k], L_mm)) - L_mm)
        d.joint(f"{j}_theta_b").qpos = theta[p, k] / 2
        d.joint(f"{j}_phi_b").qpos = -phi[p, k]

    def reduced_pose(d, p, k):
        for pivot in "ab":
            d.joint(f"j{k + 1}_{pivot}x").qpos = a[p, k]
            d.joint(f"j{k + 1}_{pivot}y").qpos = b[p, k]

    def mount_pose(d, p, k):
        d.joint(f"j{k + 1}_x").qpos = hinge[k][0][p]
        d.joint(f"j{k + 1}_y").qpos = hinge[k][1][p]

    out = []
    for key, name, pose, ref in (
        ("mjcf_exact", "fk_mujoco_vs_kinematics", exact_pose, frames),
        ("mjcf", "fk_mujoco_reduced_vs_kinematics", reduced_pose, reduced),
        ("mjcf_mount_model", "fk_mujoco_mount_vs_kinematics", mount_pose, mounted),
    ):
        if key not in robot:
            continue
        worst = _fk_worst_m(exp.root, robot[key], n, pose, ref)
        out.append(
            CheckResult(
                name,
                worst <= FK_TOLERANCE_M,
                worst,
                FK_TOLERANCE_M,
                "m",
                robot[key],
                f"{FK_POSES} random poses within the joint limits, every panel origin",
            )
        )
    return out


def _fk_worst_m(root: Path, rel: str, n: int, pose, ref: np.ndarray) -> float:
    """The farthest any panel origin of the MJCF ``rel`` (in the mount frame ``bvsr_mount``), posed
    by ``pose(d, p, k)`` for each of :data:`FK_POSES` poses, lies from ``ref`` (poses x panels x
    4 x 4, mm), m."""
    import mujoco

    with _quiet_cwd(root):
        m = mujoco.MjModel.from_xml_path(str(root / rel))
    d = mujoco.MjData(m)
    mount = m.body("bvsr_mount").id
    worst = 0.0
    for p in range(FK_POSES):
        d.qpos[:] = m.qpos0
        for k in range(n):
            pose(d, p, k)
        mujoco.mj_kinematics(m, d)
        R0, p0 = d.xmat[mount].reshape(3, 3), d.xpos[mount]
        for k in range(1, n + 1):
            pos_tail_m = R0.T @ (d.xpos[m.body(f"panel{k}").id] - p0)
            worst = max(worst, float(np.linalg.norm(pos_tail_m - units.mm_to_m(ref[p, k, :3, 3]))))
    return worst


#: The folders under ``robot/`` that :func:`check_robot` never opens: the host scenes the build's
#: quadruped stage writes after the robot checks may have run.
NOT_READ = ("robot/quadruped/",)


def robot_reads(exp: Export) -> tuple[list[str], object]:
    """What :func:`check_robot` reads: every file under ``robot/`` but the quadruped scene's
    folder (:data:`NOT_READ`, written later in a build) and the parameter file, the manifest's
    ``robot`` section, the tail's mass and the parameter file's name."""
    root = exp.root
    files = sorted(
        p.relative_to(root).as_posix()
        for p in (root / "robot").rglob("*")
        if p.is_file() and not p.relative_to(root).as_posix().startswith(NOT_READ)
    )
    params = exp.manifest.get("params_file")
    return files + ([params] if params else []), {
        "robot": exp.manifest.get("robot"),
        "mass_g": exp.manifest.get("mass_g"),
        "params_file": params,
    }


def _robot_first(exp: Export) -> list[CheckResult]:
    return [*check_inertias(exp), *check_urdf_tools(exp), *check_mujoco(exp, MUJOCO_FILES[:2])]


def _robot_second(exp: Export) -> list[CheckResult]:
    return [*check_mujoco(exp, MUJOCO_FILES[2:]), *check_pybullet(exp), *check_fk(exp)]


#: :func:`check_robot` in two parts of about the same time, in its order: a build's two processes
#: each take one when they are free (``checks.run.claim_robot_checks``), where the whole would run
#: on one core at the build's end while the other stood idle (an edit that moves no solid).
ROBOT_PARTS = (
    (_robot_first, "robot descriptions (inertias, URDF tools, MuJoCo: URDF, MJCF)"),
    (_robot_second, "robot descriptions (MuJoCo: per-segment, exact chain; PyBullet, FK)"),
)


def check_robot(exp: Export) -> list[CheckResult]:
    if "robot" not in exp.manifest:
        return []
    return [r for part, _what in ROBOT_PARTS for r in part(exp)]

"""Sends a tail to a running OCP CAD Viewer: how build123d users look at their models.

The viewer runs in VS Code (the OCP CAD Viewer extension) or standalone in a browser
(``python -m ocp_viewer``, port 3939); ``ocp_vscode.show`` tessellates the B-rep and sends it over a
websocket. Each instance goes as its own object, named as in the manifest, with the colour and
opacity of :mod:`bvsr_cad.colors`. Both the client and a listening viewer are optional: without them
:class:`ViewerUnavailable` says how to get one.
"""

from __future__ import annotations

import importlib.util
import os
import socket
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..colors import ALPHA
from ..errors import BadInput

if TYPE_CHECKING:  # the CAD imports take seconds: `bvsr show` refuses a missing viewer before them
    import build123d as bd

    from ..assembly.assemble import Assembly

#: The port the viewer listens on unless told otherwise (ocp_vscode's and ocp_viewer's default).
DEFAULT_PORT = 3939
HOW_TO_START = (
    "install the viewer extra (pip install 'bvsr_cad[viewer]') and start one: "
    "`python -m ocp_viewer` (standalone, then open http://127.0.0.1:{port} in a browser), or "
    "the OCP CAD Viewer extension in VS Code"
)


#: Tessellation of a quick look: ocp_vscode's deviation (relative to each object's size; its default
#: 0.1) and angular tolerance (rad; its default 0.2), as coarse as the report's view (0.6 rad): a
#: quick look is waited for after every save, and tessellation is most of a send's time.
COARSE = {"deviation": 0.5, "angular_tolerance": 0.6}


class ViewerUnavailable(RuntimeError, BadInput):
    """No OCP CAD Viewer to send to: the client (``ocp_vscode``) is not installed, or nothing
    listens on the port."""


def viewer_port(port: int | None = None) -> int:
    """The port of a listening viewer: ``port``, else ``$OCP_PORT``, else 3939.

    Raises:
        ViewerUnavailable: ``ocp_vscode`` is not installed, or no viewer listens there (the message
            says how to start one).
    """
    if port is None:
        env = os.environ.get("OCP_PORT", "")
        port = int(env) if env.isdigit() and int(env) > 0 else DEFAULT_PORT
    if importlib.util.find_spec("ocp_vscode") is None:
        raise ViewerUnavailable(
            "showing a tail needs OCP CAD Viewer's client (ocp_vscode is not installed): "
            + HOW_TO_START.format(port=port)
        )
    if not _listening(port):
        raise ViewerUnavailable(
            f"no OCP CAD Viewer listens on port {port}: " + HOW_TO_START.format(port=port)
        )
    return port


def _listening(port: int, host: str = "127.0.0.1") -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(1.0)
        return s.connect_ex((host, port)) == 0


def show_compound(
    compound: bd.Compound,
    kinds: dict[str, str],
    port: int | None = None,
    keep_camera: bool = False,
    coarse: bool = False,
) -> list[str]:
    """Send ``compound``'s children (labelled, coloured: :meth:`bvsr_cad.api.Tail.assembly` or
    :meth:`~bvsr_cad.api.Tail.posed`) to the viewer on ``port``, one object per child.

    Args:
        compound: the tail.
        kinds: instance name -> part kind (the opacity's key in :data:`bvsr_cad.colors.ALPHA`).
        port: as :func:`viewer_port`.
        keep_camera: leave the viewer's camera where it is (a re-send of the same tail), else frame
            it.
        coarse: tessellate at :data:`COARSE` (``bvsr watch --show``: seconds count) instead of the
            viewer's own settings.

    Returns:
        The names sent, in order.

    Raises:
        ViewerUnavailable: as :func:`viewer_port`.
    """
    port = viewer_port(port)
    from ocp_vscode import Camera, ignore_camera_warnings, set_port, show

    set_port(port)
    if keep_camera:
        # its warning that KEEP may leave the objects out of view: the tail is the same one
        ignore_camera_warnings()
    children = list(compound.children)
    names = [c.label for c in children]
    quality = COARSE if coarse else {}
    show(
        *children,
        names=names,
        colors=[tuple(c.color)[:3] for c in children],
        alphas=[ALPHA.get(kinds.get(n, ""), 1.0) for n in names],
        progress="",
        reset_camera=Camera.KEEP if keep_camera else Camera.RESET,
        **quality,
    )
    return names


def assembly_sender(
    port: int | None = None, say: Callable[[str], None] | None = None
) -> Callable[[Assembly], None]:
    """A callback for :func:`bvsr_cad.pipeline.stages.build_export` (``on_assembly``): sends the
    tail at rest as soon as its assembly is built. It tessellates copies of the parts, not the
    build's solids (OCCT keeps the finest triangulation a solid was given, and the build's meshes
    must not depend on what was shown); a viewer gone away is said, not raised (the build goes
    on)."""
    from ..assembly.placed import PlacedShape, labelled_compound
    from ..parts.kernel import fresh_copy

    say = say or (lambda _m: None)
    sent = []

    def send(asm: Assembly) -> None:
        copies = {name: fresh_copy(part.solid) for name, part in asm.parts.items()}
        placed = [
            PlacedShape(i.name, asm.part_of(i).kind, copies[i.part], i.transform)
            for i in asm.instances
        ]
        try:
            names = show_compound(
                labelled_compound(placed, asm.spec.name),
                {p.name: p.kind for p in placed},
                port,
                keep_camera=bool(sent),
                coarse=True,
            )
        except ViewerUnavailable as exc:
            say(f"not shown: {exc}")
            return
        sent.append(names)
        say(f"shown in OCP CAD Viewer: {len(names)} instances")

    return send


__all__ = ["DEFAULT_PORT", "ViewerUnavailable", "assembly_sender", "show_compound", "viewer_port"]

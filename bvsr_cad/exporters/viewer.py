"""Writes the report's interactive 3D view into an export: ``report/viewer.js`` and one data file per scene.

The viewer is a small WebGL 1 program in plain JavaScript (:data:`VIEWER_JS`,
no library, nothing fetched from the network): orbit by dragging, zoom with
the wheel, pan with shift-drag or right-drag, double-click to reset; flat
Lambert shading (a face normal per triangle, lit from over the viewer's
shoulder), one colour per object from :mod:`bvsr_cad.colors`, translucent
objects drawn after the opaque ones.

Scene data: ``report/viewer_<scene>.js``, each one call
``BVSRViewer.addScene({...})`` with a JSON object. They are scripts and not
``.json`` files because browsers refuse ``fetch`` of ``file://`` URLs but load
a ``<script src>`` from disk, so ``report.html`` works opened straight from the
export folder. The object::

    name, title, note     strings
    up, eye               the scene's up axis and the direction the camera looks from (3 numbers each)
    buffers               base64 strings of little-endian arrays: float32 x, y, z per vertex (mm)
                          or uint32 vertex indices, three per triangle
    meshes                [{"positions": buffer index, "triangles": buffer index}]
    objects               [{"label", "kind", "mesh": mesh index, "rgb": [r, g, b] in 0..1,
                            "alpha", "transform": 16 numbers, row-major 4 x 4, mesh frame -> scene (mm)}]

Identical arrays are stored once per scene (the 30 SOAs at rest share one
mesh; posed, they share their triangles).
"""

from __future__ import annotations

import base64
import hashlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.poses import ViewScene

#: The viewer's data format (``viewer.format`` in the manifest).
FORMAT = "bvsr-viewer-1"
#: Where the viewer lives, relative to the export root.
SCRIPT = "report/viewer.js"
#: The JavaScript call each scene file makes.
CALL = "BVSRViewer.addScene("


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def scene_json(scene: ViewScene) -> dict[str, Any]:
    """The scene as the viewer reads it (see the module docstring)."""
    buffers: list[str] = []
    by_digest: dict[bytes, int] = {}
    meshes: list[dict[str, int]] = []
    mesh_of: dict[tuple[int, int], int] = {}

    def buffer(a: np.ndarray) -> int:
        raw = np.ascontiguousarray(a)
        key = hashlib.sha1(raw.dtype.str.encode() + raw.tobytes()).digest()
        if key not in by_digest:
            by_digest[key] = len(buffers)
            buffers.append(_b64(raw))
        return by_digest[key]

    objects = []
    for o in scene.objects:
        tris = np.asarray(o.triangles)
        if tris.size and int(tris.max()) >= len(o.vertices_mm):
            raise ValueError(f"{scene.name}/{o.label}: triangle index {int(tris.max())} beyond "
                             f"{len(o.vertices_mm)} vertices")
        pair = (buffer(np.asarray(o.vertices_mm, "<f4")), buffer(tris.astype("<u4")))
        if pair not in mesh_of:
            mesh_of[pair] = len(meshes)
            meshes.append({"positions": pair[0], "triangles": pair[1]})
        objects.append({"label": o.label, "kind": o.kind, "mesh": mesh_of[pair],
                        "rgb": [round(float(c), 4) for c in o.rgb], "alpha": round(float(o.alpha), 4),
                        "transform": [round(float(v), 6) for v in np.asarray(o.transform, float).ravel()]})
    return {"format": FORMAT, "name": scene.name, "title": scene.title, "note": scene.note,
            "up": [float(v) for v in scene.up], "eye": [round(float(v), 6) for v in scene.eye_direction],
            "buffers": buffers, "meshes": meshes, "objects": objects}


def write_viewer(root: Path, scenes: Sequence[ViewScene]) -> dict[str, Any]:
    """Write ``report/viewer.js`` and ``report/viewer_<scene>.js`` for every scene under ``root``.

    Args:
        root: the export folder.
        scenes: from :func:`bvsr_cad.analysis.poses.viewer_scenes`.

    Returns:
        The manifest's ``viewer`` entry: ``{"viewer": {"script", "format", "scenes": [...], "bytes"}}``.

    Raises:
        ValueError: two scenes share a name, or a triangle indexes a vertex its mesh does not have.
    """
    names = [s.name for s in scenes]
    if len(set(names)) != len(names):
        raise ValueError(f"viewer scenes must have distinct names, got {names}")
    out = root / "report"
    out.mkdir(parents=True, exist_ok=True)
    (root / SCRIPT).write_text(VIEWER_JS)
    entries = []
    total = len(VIEWER_JS.encode())
    for scene in scenes:
        rel = f"report/viewer_{scene.name}.js"
        text = CALL + json.dumps(scene_json(scene), separators=(",", ":")) + ");\n"
        (root / rel).write_text(text)
        total += len(text)
        entries.append({"name": scene.name, "title": scene.title, "file": rel, "objects": len(scene.objects),
                        "triangles": scene.triangle_count, "bytes": len(text)})
    return {"viewer": {"script": SCRIPT, "format": FORMAT, "scenes": entries, "bytes": total}}


VIEWER_JS = r"""/* BVSR report viewer: WebGL 1, plain JavaScript, no library, nothing fetched from the network.
   Scene data arrive as scripts calling BVSRViewer.addScene({...}) (see bvsr_cad/exporters/viewer.py). */
(function () {
  "use strict";
  var V = window.BVSRViewer = window.BVSRViewer || {};
  V.scenes = V.scenes || {};
  var waiting = {};
  V.addScene = function (data) {
    V.scenes[data.name] = data;
    var cb = waiting[data.name];
    if (cb) { delete waiting[data.name]; cb(data); }
  };

  function bytes(s) {
    var bin = atob(s), n = bin.length, u = new Uint8Array(n);
    for (var i = 0; i < n; i++) u[i] = bin.charCodeAt(i);
    return u.buffer;
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
  function scale(a, s) { return [a[0] * s, a[1] * s, a[2] * s]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function norm(a) { var l = Math.sqrt(dot(a, a)) || 1; return scale(a, 1 / l); }
  /* 4 x 4 matrices, column-major as WebGL takes them. */
  function mul(a, b) {
    var o = new Float32Array(16);
    for (var c = 0; c < 4; c++) for (var r = 0; r < 4; r++) {
      var s = 0;
      for (var k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      o[c * 4 + r] = s;
    }
    return o;
  }
  function perspective(fovy, aspect, near, far) {
    var t = 1 / Math.tan(fovy / 2), o = new Float32Array(16);
    o[0] = t / aspect; o[5] = t; o[10] = (far + near) / (near - far); o[11] = -1; o[14] = 2 * far * near / (near - far);
    return o;
  }
  function lookAt(eye, target, up) {
    var z = norm(sub(eye, target)), x = norm(cross(up, z)), y = cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
                             -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
  }
  function fromRows(t) {
    var o = new Float32Array(16);
    for (var r = 0; r < 4; r++) for (var c = 0; c < 4; c++) o[c * 4 + r] = t[r * 4 + c];
    return o;
  }
  function apply(m, p) {
    return [m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12], m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
            m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14]];
  }

  var VS = "attribute vec3 p; attribute vec3 n; uniform mat4 M; uniform mat4 VP; uniform mat3 N; varying vec3 vn;" +
           "void main() { vn = N * n; gl_Position = VP * M * vec4(p, 1.0); }";
  var FS = "precision mediump float; uniform vec3 c; uniform float a; varying vec3 vn;" +
           "void main() { vec3 nn = normalize(vn); if (!gl_FrontFacing) nn = -nn;" +
           " float d = max(dot(nn, normalize(vec3(0.35, 0.55, 0.76))), 0.0);" +
           " gl_FragColor = vec4(c * (0.3 + 0.7 * d), a); }";
  var BACKGROUND = [0.93, 0.95, 0.97];
  var FOV = 35 * Math.PI / 180;

  function Viewer(opts) {
    var self = this;
    this.opts = opts;
    this.canvas = document.getElementById(opts.canvas);
    this.info = opts.info ? document.getElementById(opts.info) : null;
    this.built = {};
    this.scene = null;
    var gl = null;
    try {
      gl = this.canvas.getContext("webgl", {antialias: true, preserveDrawingBuffer: true}) ||
           this.canvas.getContext("experimental-webgl", {preserveDrawingBuffer: true});
    } catch (e) { gl = null; }
    this.gl = gl;
    if (!gl) { this.say("WebGL is not available in this browser: the pictures below show the same parts."); return; }
    this.prog = this.program(VS, FS);
    this.loc = {p: gl.getAttribLocation(this.prog, "p"), n: gl.getAttribLocation(this.prog, "n"),
                M: gl.getUniformLocation(this.prog, "M"), VP: gl.getUniformLocation(this.prog, "VP"),
                N: gl.getUniformLocation(this.prog, "N"), c: gl.getUniformLocation(this.prog, "c"),
                a: gl.getUniformLocation(this.prog, "a")};
    this.pending = false;
    this.bindInput();
    window.addEventListener("resize", function () { self.redraw(); });
  }
  Viewer.prototype.say = function (text) { if (this.info) this.info.textContent = text; };
  Viewer.prototype.program = function (vs, fs) {
    var gl = this.gl, p = gl.createProgram();
    [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]].forEach(function (s) {
      var sh = gl.createShader(s[0]);
      gl.shaderSource(sh, s[1]); gl.compileShader(sh);
      if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(sh));
      gl.attachShader(p, sh);
    });
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  };
  /* One GL buffer per mesh: every triangle's corners with its face normal (flat shading). */
  Viewer.prototype.build = function (data) {
    var gl = this.gl, arrays = data.buffers.map(bytes), lo = [1e30, 1e30, 1e30], hi = [-1e30, -1e30, -1e30];
    var meshes = data.meshes.map(function (m) {
      var P = new Float32Array(arrays[m.positions]), T = new Uint32Array(arrays[m.triangles]);
      var out = new Float32Array(T.length * 6), mlo = [1e30, 1e30, 1e30], mhi = [-1e30, -1e30, -1e30];
      for (var t = 0; t < T.length; t += 3) {
        var a = T[t] * 3, b = T[t + 1] * 3, c = T[t + 2] * 3;
        var e1 = [P[b] - P[a], P[b + 1] - P[a + 1], P[b + 2] - P[a + 2]];
        var e2 = [P[c] - P[a], P[c + 1] - P[a + 1], P[c + 2] - P[a + 2]];
        var nrm = norm(cross(e1, e2));
        [a, b, c].forEach(function (v, k) {
          var o = (t + k) * 6;
          out[o] = P[v]; out[o + 1] = P[v + 1]; out[o + 2] = P[v + 2];
          out[o + 3] = nrm[0]; out[o + 4] = nrm[1]; out[o + 5] = nrm[2];
        });
      }
      for (var i = 0; i < P.length; i += 3) for (var d = 0; d < 3; d++) {
        mlo[d] = Math.min(mlo[d], P[i + d]); mhi[d] = Math.max(mhi[d], P[i + d]);
      }
      var buf = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.bufferData(gl.ARRAY_BUFFER, out, gl.STATIC_DRAW);
      return {buf: buf, count: T.length, lo: mlo, hi: mhi};
    });
    var objects = data.objects.map(function (o) {
      var M = fromRows(o.transform), m = meshes[o.mesh], centre = [0, 0, 0];
      for (var k = 0; k < 8; k++) {
        var q = apply(M, [k & 1 ? m.hi[0] : m.lo[0], k & 2 ? m.hi[1] : m.lo[1], k & 4 ? m.hi[2] : m.lo[2]]);
        for (var d = 0; d < 3; d++) { lo[d] = Math.min(lo[d], q[d]); hi[d] = Math.max(hi[d], q[d]); }
        centre = add(centre, scale(q, 1 / 8));
      }
      return {M: M, mesh: m, rgb: o.rgb, alpha: o.alpha, centre: centre, kind: o.kind, label: o.label};
    });
    var tris = meshes.length ? data.objects.reduce(function (s, o) { return s + meshes[o.mesh].count / 3; }, 0) : 0;
    return {data: data, objects: objects, centre: scale(add(lo, hi), 0.5), lo: lo, hi: hi,
            radius: Math.max(0.5 * Math.sqrt(dot(sub(hi, lo), sub(hi, lo))), 1e-3), triangles: tris};
  };
  Viewer.prototype.reset = function () {
    var s = this.scene, up = norm(s.data.up), e = norm(s.data.eye);
    var a = sub(e, scale(up, dot(e, up)));
    if (dot(a, a) < 1e-9) a = Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
    a = norm(sub(a, scale(up, dot(a, up))));
    this.cam = {up: up, a: a, b: cross(up, a), az: 0, el: Math.asin(Math.max(-1, Math.min(1, dot(e, up)))),
                target: s.centre.slice(), dist: 1};
    /* The distance at which every corner of the scene's box is inside the view, with a margin. */
    var z = norm(sub(this.eye(), s.centre)), x = norm(cross(up, z)), y = cross(z, x);
    var cv = this.canvas, ty = Math.tan(FOV / 2), tx = ty * Math.max(0.2, cv.clientWidth / (cv.clientHeight || 1));
    var dist = 0;
    for (var k = 0; k < 8; k++) {
      var q = sub([k & 1 ? s.hi[0] : s.lo[0], k & 2 ? s.hi[1] : s.lo[1], k & 4 ? s.hi[2] : s.lo[2]], s.centre);
      dist = Math.max(dist, dot(q, z) + Math.abs(dot(q, x)) / tx, dot(q, z) + Math.abs(dot(q, y)) / ty);
    }
    this.cam.dist = 1.1 * Math.max(dist, 1e-3);
  };
  Viewer.prototype.eye = function () {
    var c = this.cam, ce = Math.cos(c.el);
    var dir = add(add(scale(c.a, ce * Math.cos(c.az)), scale(c.b, ce * Math.sin(c.az))), scale(c.up, Math.sin(c.el)));
    return add(c.target, scale(dir, c.dist));
  };
  Viewer.prototype.show = function (name) {
    var self = this, entry = null;
    this.opts.scenes.forEach(function (s) { if (s.name === name) entry = s; });
    if (!entry || !this.gl) return;
    (this.opts.buttons ? document.querySelectorAll("#" + this.opts.buttons + " button") : []).forEach(function (b) {
      b.className = b.getAttribute("data-scene") === name ? "active" : "";
    });
    var ready = function (data) {
      if (!self.built[name]) self.built[name] = self.build(data);
      self.scene = self.built[name];
      self.reset();
      var kinds = {}, legend = [];
      data.objects.forEach(function (o) { if (!kinds[o.kind]) { kinds[o.kind] = 1; legend.push(o); } });
      if (self.info) {
        self.info.textContent = "";
        var t = document.createElement("b"); t.textContent = data.title + ". ";
        self.info.appendChild(t);
        self.info.appendChild(document.createTextNode(data.note + ". " + data.objects.length + " objects, " +
                                                       self.scene.triangles + " triangles. "));
        legend.forEach(function (o) {
          var sw = document.createElement("span");
          sw.className = "swatch";
          sw.style.background = "rgb(" + o.rgb.map(function (v) { return Math.round(255 * v); }).join(",") + ")";
          self.info.appendChild(sw);
          self.info.appendChild(document.createTextNode(o.kind.replace(/_/g, " ") + " "));
        });
      }
      self.render();
    };
    if (V.scenes[name]) return ready(V.scenes[name]);
    this.say("loading " + entry.title + " ...");
    waiting[name] = ready;
    var tag = document.createElement("script");
    tag.src = entry.file;
    tag.onerror = function () { self.say("could not load " + entry.file + " (is the export folder complete?)"); };
    document.head.appendChild(tag);
  };
  Viewer.prototype.redraw = function () {
    var self = this;
    if (this.pending || !this.scene) return;
    this.pending = true;
    window.requestAnimationFrame(function () { self.pending = false; self.render(); });
  };
  Viewer.prototype.render = function () {
    var gl = this.gl, cv = this.canvas, s = this.scene, L = this.loc;
    if (!gl || !s) return;
    var dpr = window.devicePixelRatio || 1, w = Math.max(1, Math.round(cv.clientWidth * dpr)),
        h = Math.max(1, Math.round(cv.clientHeight * dpr));
    if (cv.width !== w || cv.height !== h) { cv.width = w; cv.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    var c = this.cam, eye = this.eye(), view = lookAt(eye, c.target, c.up);
    var near = Math.max(c.dist - 1.6 * s.radius, c.dist * 0.01, 0.01), far = c.dist + 1.6 * s.radius;
    gl.useProgram(this.prog);
    gl.uniformMatrix4fv(L.VP, false, mul(perspective(FOV, w / h, near, far), view));
    gl.enableVertexAttribArray(L.p); gl.enableVertexAttribArray(L.n);
    var draw = function (o) {
      var mv = mul(view, o.M);
      gl.uniformMatrix4fv(L.M, false, o.M);
      gl.uniformMatrix3fv(L.N, false,
                          new Float32Array([mv[0], mv[1], mv[2], mv[4], mv[5], mv[6], mv[8], mv[9], mv[10]]));
      gl.uniform3fv(L.c, o.rgb); gl.uniform1f(L.a, o.alpha);
      gl.bindBuffer(gl.ARRAY_BUFFER, o.mesh.buf);
      gl.vertexAttribPointer(L.p, 3, gl.FLOAT, false, 24, 0);
      gl.vertexAttribPointer(L.n, 3, gl.FLOAT, false, 24, 12);
      gl.drawArrays(gl.TRIANGLES, 0, o.mesh.count);
    };
    var clear = [];
    s.objects.forEach(function (o) { if (o.alpha >= 0.999) draw(o); else clear.push(o); });
    if (clear.length) {  /* translucent last, far to near, without writing depth */
      var far2 = function (o) { var d = sub(o.centre, eye); return dot(d, d); };
      clear.sort(function (p, q) { return far2(q) - far2(p); });
      gl.enable(gl.BLEND); gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA); gl.depthMask(false);
      clear.forEach(draw);
      gl.depthMask(true); gl.disable(gl.BLEND);
    }
  };
  Viewer.prototype.bindInput = function () {
    var self = this, cv = this.canvas, drag = null;
    cv.addEventListener("contextmenu", function (e) { e.preventDefault(); });
    cv.addEventListener("pointerdown", function (e) {
      if (!self.scene) return;
      drag = {x: e.clientX, y: e.clientY, pan: e.button === 2 || e.button === 1 || e.shiftKey};
      if (cv.setPointerCapture) cv.setPointerCapture(e.pointerId);
      e.preventDefault();
    });
    cv.addEventListener("pointermove", function (e) {
      if (!drag) return;
      var dx = e.clientX - drag.x, dy = e.clientY - drag.y, c = self.cam;
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.pan) {
        var z = norm(sub(self.eye(), c.target)), x = norm(cross(c.up, z)), y = cross(z, x);
        var k = 2 * c.dist * Math.tan(FOV / 2) / Math.max(1, cv.clientHeight);
        c.target = add(c.target, add(scale(x, -dx * k), scale(y, dy * k)));
      } else {
        c.az -= dx * 0.008;
        c.el = Math.max(-1.55, Math.min(1.55, c.el + dy * 0.008));
      }
      self.redraw();
    });
    var end = function () { drag = null; };
    cv.addEventListener("pointerup", end);
    cv.addEventListener("pointercancel", end);
    cv.addEventListener("wheel", function (e) {
      if (!self.scene) return;
      e.preventDefault();
      var c = self.cam, r = self.scene.radius;
      c.dist = Math.max(0.05 * r, Math.min(40 * r, c.dist * Math.exp(0.0015 * e.deltaY)));
      self.redraw();
    }, {passive: false});
    cv.addEventListener("dblclick", function () { if (self.scene) { self.reset(); self.redraw(); } });
  };

  /* opts: {canvas, info, buttons (ids), scenes: [{name, title, file}], initial}; "#viewer=NAME" in the
     address picks the first scene. */
  V.start = function (opts) {
    var v = new Viewer(opts);
    if (opts.buttons) {
      document.querySelectorAll("#" + opts.buttons + " button").forEach(function (b) {
        b.addEventListener("click", function () { v.show(b.getAttribute("data-scene")); });
      });
    }
    var h = decodeURIComponent(window.location.hash.slice(1)), first = opts.initial;
    if (h.indexOf("viewer=") === 0) first = h.slice(7);
    v.show(first);
    V.viewer = v;
    return v;
  };
})();
"""

"""A self-contained web page showing a segmented mesh, interactive, no network.

:func:`write_html` writes one HTML file holding the mesh as compact binary
buffers (base64 of float32 vertices, uint32 faces, one palette index per
face, uint32 boundary edges) and a small WebGL viewer: drag to rotate,
wheel or pinch to zoom, right-drag or shift-drag to pan, ``b`` toggles the
superfacet boundaries, ``r`` resets the view. Nothing is fetched from the
network, so the page opens from a file, offline, in any browser with WebGL.
"""

from __future__ import annotations

import base64
import html as _html
import json
from pathlib import Path

import numpy as np

from .errors import ParameterError
from .mesh import as_mesh

__all__ = ["write_html", "html_page"]


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def html_page(mesh, labels=None, *, title: str | None = None, info: dict | None = None,
              background: str = "#ffffff", view=None, up="y") -> str:
    """The HTML text of the viewer page (see :func:`write_html`)."""
    from .connectivity import relabel_dense
    from .viz import boundary_edges, superfacet_colors

    mesh = as_mesh(mesh)
    m = mesh.n_faces
    if labels is not None:
        labels = np.asarray(labels)
        if labels.shape != (m,) or not np.issubdtype(labels.dtype, np.integer):
            raise ParameterError(f"labels must be {m} integers, one per face; got shape "
                                 f"{labels.shape}, dtype {labels.dtype}")
        dense = relabel_dense(labels)
        colors = superfacet_colors(mesh, dense)  # (K, 3) uint8, per superfacet
        palette, color_index = np.unique(colors, axis=0, return_inverse=True)
        face_index = color_index.ravel()[dense]
        edges = boundary_edges(mesh, dense)
        n_sf = int(dense.max()) + 1
    else:
        palette = np.array([[200, 200, 200]], dtype=np.uint8)
        face_index = np.zeros(m, dtype=np.int64)
        edges = np.zeros((0, 2), dtype=np.int64)
        n_sf = 0
    if palette.shape[0] > 65535:  # pragma: no cover - greedy colouring uses ~12 colours
        raise ParameterError("too many distinct colours for the page")
    index_dtype = np.uint8 if palette.shape[0] <= 256 else np.uint16
    # used vertices only, centred and scaled to the unit ball (float32 keeps the precision)
    used, faces = np.unique(mesh.faces, return_inverse=True)
    faces = faces.reshape(-1, 3)
    v = mesh.vertices[used]
    center = (v.min(axis=0) + v.max(axis=0)) / 2
    scale = float(np.linalg.norm(v - center, axis=1).max()) or 1.0
    v = ((v - center) / scale).astype("<f4")
    if edges.size:
        edges = np.searchsorted(used, edges)
    from .viz import view_frame

    try:
        d, upv = view_frame(mesh, view, up=up)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None
    rot = np.stack([np.cross(upv, d), upv, d])  # rows: camera x, y, z in mesh coordinates
    name = title or mesh.name or "mesh"
    meta = {"name": name, "faces": m, "vertices": int(used.size), "superfacets": n_sf,
            "info": {str(k): str(v_) for k, v_ in (info or {}).items()},
            "palette": palette.astype(int).tolist(), "indexBytes": np.dtype(index_dtype).itemsize,
            "nVertices": int(used.size), "nFaces": m, "nEdges": int(edges.shape[0]),
            "background": background, "rotation": rot.T.ravel().round(6).tolist()}
    data = {"vertices": _b64(v), "faces": _b64(faces.astype("<u4")),
            "colors": _b64(face_index.astype(index_dtype)),
            "edges": _b64(np.asarray(edges, dtype="<u4"))}
    blobs = "\n".join(f'<script type="application/octet-stream" id="{k}">{b}</script>'
                      for k, b in data.items())
    return (_TEMPLATE.replace("%TITLE%", _html.escape(f"{name} - superfacets"))
            .replace("%BACKGROUND%", _html.escape(background))
            .replace("%META%", json.dumps(meta).replace("</", "<\\/"))
            .replace("%BLOBS%", blobs))


def write_html(path, mesh, labels=None, *, title: str | None = None, info: dict | None = None,
               background: str = "#ffffff", view=None, up="y") -> Path:
    """Write a self-contained interactive HTML page of a (segmented) mesh.

    Parameters
    ----------
    path : path
        Output file (``.html``), written atomically.
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray, optional
        Superfacet of each face; without it the mesh is grey.
    title : str, optional
        Shown on the page (default: the mesh name).
    info : dict, optional
        Extra lines shown on the page (e.g. the parameters of the run).
    background : str, default '#ffffff'
        CSS colour of the page.
    view, up
        Initial camera, as in :func:`superfacets.viz.view_frame`.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per face, or on a bad view.
    FileNotFoundError
        If the output folder does not exist.

    Notes
    -----
    Size is about 32 bytes of base64 per face (a 1M-face mesh gives a
    ~35 MB page); the browser builds flat-shaded triangles from it.
    """
    from .io import atomic_write

    text = html_page(mesh, labels, title=title, info=info, background=background, view=view,
                     up=up)
    return atomic_write(path, text.encode("utf-8"))


_TEMPLATE = r"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>%TITLE%</title>
<style>
  html, body { margin: 0; height: 100%; overflow: hidden; background: %BACKGROUND%;
               font: 14px/1.4 system-ui, sans-serif; }
  canvas { display: block; width: 100%; height: 100%; touch-action: none; cursor: grab; }
  #info { position: absolute; top: 8px; left: 10px; padding: 6px 10px; border-radius: 6px;
          background: rgba(255,255,255,.85); color: #222; pointer-events: none; }
  #info b { font-size: 16px; }
  #help { position: absolute; bottom: 8px; left: 10px; color: #555; font-size: 12px; }
  #error { position: absolute; top: 40%; width: 100%; text-align: center; color: #a00; }
</style>
</head>
<body>
<canvas id="view"></canvas>
<div id="info"></div>
<div id="help">drag: rotate &middot; wheel: zoom &middot; shift/right-drag: pan &middot;
  b: boundaries &middot; r: reset</div>
<div id="error"></div>
<script type="application/json" id="meta">%META%</script>
%BLOBS%
<script>
"use strict";
(function () {
  const meta = JSON.parse(document.getElementById("meta").textContent);
  function bytes(id) {
    const s = atob(document.getElementById(id).textContent.trim());
    const out = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
    return out.buffer;
  }
  const info = document.getElementById("info");
  let lines = ["<b>" + esc(meta.name) + "</b>",
               meta.faces.toLocaleString("en") + " faces" +
               (meta.superfacets ? ", " + meta.superfacets.toLocaleString("en") + " superfacets" : "")];
  for (const [k, v] of Object.entries(meta.info)) lines.push(esc(k) + ": " + esc(v));
  info.innerHTML = lines.join("<br>");
  function esc(t) { return String(t).replace(/[&<>"]/g, c => ({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}[c])); }

  const canvas = document.getElementById("view");
  const gl = canvas.getContext("webgl", {antialias: true, preserveDrawingBuffer: true});
  if (!gl) { document.getElementById("error").textContent = "WebGL is not available in this browser."; return; }

  const V = new Float32Array(bytes("vertices"));
  const F = new Uint32Array(bytes("faces"));
  const C = meta.indexBytes === 1 ? new Uint8Array(bytes("colors")) : new Uint16Array(bytes("colors"));
  const E = new Uint32Array(bytes("edges"));
  const nf = meta.nFaces;
  // three vertices per face with the face's colour; the flat normal comes from screen-space
  // derivatives in the fragment shader, so no normal buffer is needed
  const pos = new Float32Array(nf * 9), col = new Uint8Array(nf * 9);
  for (let f = 0; f < nf; f++) {
    const p = meta.palette[C[f]];
    for (let j = 0; j < 3; j++) {
      const a = 3 * F[3 * f + j], o = 9 * f + 3 * j;
      pos[o] = V[a]; pos[o + 1] = V[a + 1]; pos[o + 2] = V[a + 2];
      col[o] = p[0]; col[o + 1] = p[1]; col[o + 2] = p[2];
    }
  }
  const epos = new Float32Array(E.length * 3);
  for (let i = 0; i < E.length; i++) {
    epos[3 * i] = V[3 * E[i]]; epos[3 * i + 1] = V[3 * E[i] + 1]; epos[3 * i + 2] = V[3 * E[i] + 2];
  }

  function shader(type, src) {
    const s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  function program(vs, fs) {
    const p = gl.createProgram();
    gl.attachShader(p, shader(gl.VERTEX_SHADER, vs)); gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p); return p;
  }
  if (!gl.getExtension("OES_standard_derivatives")) {
    document.getElementById("error").textContent = "This browser's WebGL lacks OES_standard_derivatives."; return;
  }
  const surf = program(
    "attribute vec3 p; attribute vec3 c; uniform mat4 mv, pr; varying vec3 vp, vc;" +
    "void main() { vec4 q = mv * vec4(p, 1.0); vp = q.xyz; vc = c / 255.0; gl_Position = pr * q; }",
    "#extension GL_OES_standard_derivatives : enable\n" +
    "precision highp float; varying vec3 vp, vc;" +
    "void main() { vec3 n = normalize(cross(dFdx(vp), dFdy(vp)));" +
    " float d = abs(dot(n, normalize(-vp))); gl_FragColor = vec4(vc * (0.35 + 0.65 * d), 1.0); }");
  const line = program(
    "attribute vec3 p; uniform mat4 mv, pr; void main() { gl_Position = pr * mv * vec4(p, 1.0); }",
    "precision mediump float; void main() { gl_FragColor = vec4(0.05, 0.05, 0.05, 1.0); }");
  function buffer(data) { const b = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW); return b; }
  const bp = buffer(pos), bc = buffer(col), be = buffer(epos);

  // camera: rotation matrix R (column-major 3x3), distance, pan
  let R, dist, pan, showEdges = true;
  function reset() { R = meta.rotation.slice(); dist = 3.6; pan = [0, 0]; }
  function rotX(t) { const c = Math.cos(t), s = Math.sin(t); return [1, 0, 0, 0, c, s, 0, -s, c]; }
  function rotY(t) { const c = Math.cos(t), s = Math.sin(t); return [c, 0, -s, 0, 1, 0, s, 0, c]; }
  function mul3(a, b) {
    const o = new Array(9);
    for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++)
      o[3 * j + i] = a[i] * b[3 * j] + a[3 + i] * b[3 * j + 1] + a[6 + i] * b[3 * j + 2];
    return o;
  }
  reset();

  function draw() {
    const w = canvas.clientWidth * devicePixelRatio | 0, h = canvas.clientHeight * devicePixelRatio | 0;
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    gl.viewport(0, 0, w, h);
    const bg = getComputedStyle(document.body).backgroundColor.match(/\d+/g).map(Number);
    gl.clearColor(bg[0] / 255, bg[1] / 255, bg[2] / 255, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    const mv = [R[0], R[1], R[2], 0, R[3], R[4], R[5], 0, R[6], R[7], R[8], 0, pan[0], pan[1], -dist, 1];
    const fov = 0.6, near = 0.01, far = 100, asp = w / Math.max(h, 1), t = 1 / Math.tan(fov / 2);
    const pr = [t / asp, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0];
    gl.enable(gl.POLYGON_OFFSET_FILL); gl.polygonOffset(1, 1);
    gl.useProgram(surf);
    gl.uniformMatrix4fv(gl.getUniformLocation(surf, "mv"), false, mv);
    gl.uniformMatrix4fv(gl.getUniformLocation(surf, "pr"), false, pr);
    attrib(surf, "p", bp, 3, gl.FLOAT, false);
    attrib(surf, "c", bc, 3, gl.UNSIGNED_BYTE, false);
    gl.drawArrays(gl.TRIANGLES, 0, nf * 3);
    gl.disableVertexAttribArray(gl.getAttribLocation(surf, "c"));
    if (showEdges && E.length) {
      gl.useProgram(line);
      gl.uniformMatrix4fv(gl.getUniformLocation(line, "mv"), false, mv);
      gl.uniformMatrix4fv(gl.getUniformLocation(line, "pr"), false, pr);
      attrib(line, "p", be, 3, gl.FLOAT, false);
      gl.drawArrays(gl.LINES, 0, E.length);
    }
    document.body.dataset.drawn = "1";
  }
  function attrib(p, name, buf, size, type, norm) {
    const loc = gl.getAttribLocation(p, name); if (loc < 0) return;
    gl.bindBuffer(gl.ARRAY_BUFFER, buf); gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, size, type, norm, 0, 0);
  }
  let pending = false;
  function redraw() { if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; draw(); }); } }

  let drag = null;
  canvas.addEventListener("contextmenu", e => e.preventDefault());
  canvas.addEventListener("pointerdown", e => { drag = {x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2}; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointermove", e => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y; drag.x = e.clientX; drag.y = e.clientY;
    if (drag.pan) { const s = dist / canvas.clientHeight; pan[0] += dx * s; pan[1] -= dy * s; }
    else { R = mul3(rotY(dx * 0.01), R); R = mul3(rotX(dy * 0.01), R); }
    redraw();
  });
  canvas.addEventListener("wheel", e => { e.preventDefault(); dist = Math.min(50, Math.max(0.05, dist * Math.exp(e.deltaY * 0.001))); redraw(); }, {passive: false});
  addEventListener("keydown", e => {
    if (e.key === "b") { showEdges = !showEdges; redraw(); }
    if (e.key === "r") { reset(); redraw(); }
  });
  addEventListener("resize", redraw);
  draw();
})();
</script>
</body>
</html>
"""

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
  const isPoints = meta.points !== undefined;
  let lines = ["<b>" + esc(meta.name) + "</b>",
               isPoints ? meta.points.toLocaleString("en") + " points" +
                 (meta.superfacets ? ", " + meta.superfacets.toLocaleString("en") + " " +
                  (meta.word || "superpoints") : "")
               : meta.faces.toLocaleString("en") + " faces" +
                 (meta.superfacets ? ", " + meta.superfacets.toLocaleString("en") + " superfacets" : "")];
  for (const [k, v] of Object.entries(meta.info)) lines.push(esc(k) + ": " + esc(v));
  info.innerHTML = lines.join("<br>");
  for (const [text, rgb] of meta.legend || []) {  // (a class legend: a swatch, its name)
    const row = document.createElement("div"), swatch = document.createElement("span");
    swatch.style.cssText = "display:inline-block;width:0.9em;height:0.9em;margin-right:0.4em;" +
      "border:1px solid #444;vertical-align:middle;background:rgb(" + rgb.join(",") + ")";
    row.appendChild(swatch);
    row.appendChild(document.createTextNode(text));
    info.appendChild(row);
  }
  if (meta.legendRest) info.appendChild(document.createTextNode("and " + meta.legendRest + " more"));
  function esc(t) { return String(t).replace(/[&<>"]/g, c => ({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}[c])); }

  const canvas = document.getElementById("view");
  const gl = canvas.getContext("webgl", {antialias: true, preserveDrawingBuffer: true});
  if (!gl) { document.getElementById("error").textContent = "WebGL is not available in this browser."; return; }

  const V = new Float32Array(bytes("vertices"));
  const F = new Uint32Array(bytes("faces"));
  const C = meta.indexBytes === 1 ? new Uint8Array(bytes("colors")) : new Uint16Array(bytes("colors"));
  const E = new Uint32Array(bytes("edges"));
  const nf = meta.nFaces, np_ = isPoints ? meta.nVertices : 0;
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
  // a point cloud: one coloured sprite per point
  const ppos = isPoints ? V : new Float32Array(0), pcol = new Uint8Array(np_ * 3);
  for (let i = 0; i < np_; i++) {
    const p = meta.palette[C[i]];
    pcol[3 * i] = p[0]; pcol[3 * i + 1] = p[1]; pcol[3 * i + 2] = p[2];
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
  const dots = program(
    "attribute vec3 p; attribute vec3 c; uniform mat4 mv, pr; uniform float s; varying vec3 vc;" +
    "void main() { vec4 q = mv * vec4(p, 1.0); vc = c / 255.0; gl_Position = pr * q;" +
    " gl_PointSize = max(1.0, s / max(-q.z, 0.01)); }",
    "precision mediump float; varying vec3 vc; void main() { gl_FragColor = vec4(vc, 1.0); }");
  function buffer(data) { const b = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW); return b; }
  const bp = buffer(pos), bc = buffer(col), be = buffer(epos);
  const bpp = buffer(ppos), bpc = buffer(pcol);

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
    if (isPoints) {
      gl.useProgram(dots);
      gl.uniformMatrix4fv(gl.getUniformLocation(dots, "mv"), false, mv);
      gl.uniformMatrix4fv(gl.getUniformLocation(dots, "pr"), false, pr);
      gl.uniform1f(gl.getUniformLocation(dots, "s"), 1.5 * meta.spacing * h / (2 * Math.tan(fov / 2)));
      attrib(dots, "p", bpp, 3, gl.FLOAT, false);
      attrib(dots, "c", bpc, 3, gl.UNSIGNED_BYTE, false);
      gl.drawArrays(gl.POINTS, 0, np_);
      gl.disableVertexAttribArray(gl.getAttribLocation(dots, "c"));
      document.body.dataset.drawn = "1";
      return;
    }
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

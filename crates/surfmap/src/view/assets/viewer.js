// surfmap view: a small WebGL2 renderer for the pages `surfmap view` writes.
// Everything it draws is in the JSON document of the page (#surfmap-data): typed arrays
// as base64, decoded once; geometry is laid out per triangle corner once (so a value per
// triangle, texture seams and picking by triangle id need no index tricks) and only
// positions and normals are refilled when a slider moves.
"use strict";
(function () {
  const DATA = JSON.parse(document.getElementById("surfmap-data").textContent);
  const api = {
    data: DATA, ready: false, errors: [], frames: 0, firstFrameMs: null,
    decodeMs: null, picked: null, panels: {},
  };
  window.surfmapView = api;
  window.addEventListener("error", (e) => api.errors.push(String(e.message || e)));

  // ---------------------------------------------------------------- arrays
  const TYPES = { f32: Float32Array, u32: Uint32Array, i32: Int32Array };
  const decoded = {};
  function arr(name) {
    if (decoded[name]) return decoded[name];
    const a = DATA.arrays && DATA.arrays[name];
    if (!a) return null;
    const text = atob(a.b64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    const out = new TYPES[a.type](bytes.buffer, 0, a.length);
    decoded[name] = out;
    return out;
  }

  // ---------------------------------------------------------------- DOM helpers
  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") e.className = v;
      else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
      else e.setAttribute(k, v);
    }
    for (const c of children) if (c !== null && c !== undefined) e.append(c);
    return e;
  }
  const side = document.getElementById("side");
  function section(title, ...children) {
    const s = el("section", {}, el("h2", {}, title), ...children);
    side.append(s);
    return s;
  }
  function fmt(v) {
    if (typeof v === "number") {
      if (Number.isInteger(v)) return String(v);
      const a = Math.abs(v);
      if (a !== 0 && (a < 1e-3 || a >= 1e6)) return v.toExponential(3);
      return String(Number(v.toPrecision(5)));
    }
    if (typeof v === "boolean") return v ? "yes" : "no";
    if (v === null || v === undefined) return "–";
    return String(v);
  }
  function numbersTable(list, source) {
    if (!list || !list.length) return;
    const rows = list.map((n) =>
      el("tr", { "data-path": n.path || "" }, el("th", {}, n.label),
        el("td", { title: String(n.value) }, fmt(n.value))));
    section("Numbers", el("table", { class: "numbers", id: "numbers" }, ...rows),
      source ? el("p", { class: "small" }, "from " + source) : null);
  }
  function notes() {
    if (DATA.notes && DATA.notes.length)
      section("Notes", ...DATA.notes.map((n) => el("p", { class: "note" }, n)));
  }
  function help(lines) {
    section("Controls", el("ul", { class: "small" }, ...lines.map((l) => el("li", {}, l))));
  }

  // ---------------------------------------------------------------- matrices (column-major)
  function mul(a, b) {
    const o = new Float32Array(16);
    for (let i = 0; i < 4; i++)
      for (let j = 0; j < 4; j++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + i] * b[j * 4 + k];
        o[j * 4 + i] = s;
      }
    return o;
  }
  function perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), o = new Float32Array(16);
    o[0] = f / aspect; o[5] = f; o[10] = (far + near) / (near - far); o[11] = -1;
    o[14] = (2 * far * near) / (near - far);
    return o;
  }
  function apply(m, p) {
    const x = p[0], y = p[1], z = p[2];
    const w = m[3] * x + m[7] * y + m[11] * z + m[15];
    return [(m[0] * x + m[4] * y + m[8] * z + m[12]) / w,
      (m[1] * x + m[5] * y + m[9] * z + m[13]) / w,
      (m[2] * x + m[6] * y + m[10] * z + m[14]) / w, w];
  }
  const IDENTITY = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
  // Rotation about a unit axis, 3×3 row-major.
  function rot3(axis, angle) {
    const [x, y, z] = axis, c = Math.cos(angle), s = Math.sin(angle), t = 1 - c;
    return [t * x * x + c, t * x * y - s * z, t * x * z + s * y,
      t * x * y + s * z, t * y * y + c, t * y * z - s * x,
      t * x * z - s * y, t * y * z + s * x, t * z * z + c];
  }
  function mul3(a, b) {
    const o = new Array(9);
    for (let i = 0; i < 3; i++)
      for (let j = 0; j < 3; j++)
        o[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
    return o;
  }

  // ---------------------------------------------------------------- GL set-up
  let canvas = document.getElementById("gl");
  const overlay = document.getElementById("overlay");
  const stage = document.getElementById("stage");
  let gl = null;

  const SURFACE_VS = `#version 300 es
in vec3 a_pos; in vec3 a_nrm; in vec3 a_ref; in float a_val; in float a_flag;
uniform mat4 u_proj; uniform mat4 u_mv; uniform float u_bias;
out vec3 v_ref; out float v_val; out float v_flag; out vec3 v_n; out vec3 v_vpos;
void main() {
  vec4 p = u_mv * vec4(a_pos, 1.0);
  v_n = mat3(u_mv) * a_nrm; v_vpos = p.xyz;
  p.z += u_bias;
  gl_Position = u_proj * p;
  v_ref = a_ref; v_val = a_val; v_flag = a_flag;
}`;
  const SURFACE_FS = `#version 300 es
precision highp float;
in vec3 v_ref; in float v_val; in float v_flag; in vec3 v_n; in vec3 v_vpos;
uniform int u_mode; uniform float u_cells; uniform vec3 u_scale; uniform vec3 u_color;
uniform float u_light; uniform mat4 u_checker; uniform vec2 u_origin;
uniform sampler2D u_lut; uniform sampler2D u_tex;
out vec4 o;
void main() {
  vec3 c = u_color;
  if (u_mode == 1) {
    vec2 q = floor((v_ref.xy - u_origin) * u_cells);
    c = mod(q.x + q.y, 2.0) < 0.5 ? vec3(0.95, 0.95, 0.93) : vec3(0.22, 0.42, 0.72);
  } else if (u_mode == 2) {
    vec2 q = floor((u_checker * vec4(v_ref, 1.0)).xy);
    c = mod(q.x + q.y, 2.0) < 0.5 ? vec3(0.96, 0.94, 0.88) : vec3(0.82, 0.33, 0.18);
  } else if (u_mode == 3) {
    if (v_val < 0.0) c = vec3(0.62);
    else {
      float t = u_scale.z > 0.5
        ? (log(max(v_val, 1e-30)) - log(u_scale.x)) / (log(u_scale.y) - log(u_scale.x))
        : (v_val - u_scale.x) / (u_scale.y - u_scale.x);
      c = texture(u_lut, vec2(clamp(t, 0.0, 1.0) * 0.996 + 0.002, 0.5)).rgb;
    }
  } else if (u_mode == 4) {
    c = texture(u_tex, vec2(v_ref.x, 1.0 - v_ref.y)).rgb;
  }
  c = mix(c, vec3(0.86, 0.08, 0.12), clamp(v_flag, 0.0, 1.0) * 0.8);
  if (u_light > 0.5) {
    vec3 n = length(v_n) > 1e-12 ? normalize(v_n) : normalize(cross(dFdx(v_vpos), dFdy(v_vpos)));
    vec3 e = normalize(-v_vpos);
    float d = abs(dot(n, e));
    c = c * (0.28 + 0.72 * d) + vec3(0.12) * pow(d, 24.0);
  }
  o = vec4(c, 1.0);
}`;
  const PICK_VS = `#version 300 es
in vec3 a_pos; uniform mat4 u_mvp; flat out int v_id;
void main() { gl_Position = u_mvp * vec4(a_pos, 1.0); v_id = gl_VertexID / 3; }`;
  const PICK_FS = `#version 300 es
precision highp float; flat in int v_id; out vec4 o;
void main() { int i = v_id + 1;
  o = vec4(float(i & 255), float((i >> 8) & 255), float((i >> 16) & 255), float((i >> 24) & 255)) / 255.0; }`;
  const LINE_VS = `#version 300 es
in vec3 a_p0; in vec3 a_p1; in vec2 a_corner;
uniform mat4 u_mvp; uniform vec2 u_half; uniform float u_width;
void main() {
  vec4 c0 = u_mvp * vec4(a_p0, 1.0), c1 = u_mvp * vec4(a_p1, 1.0);
  vec4 c = a_corner.x < 0.5 ? c0 : c1;
  vec2 d = c1.xy / c1.w * u_half - c0.xy / c0.w * u_half;
  d = length(d) > 1e-9 ? normalize(d) : vec2(1.0, 0.0);
  c.xy += vec2(-d.y, d.x) * a_corner.y * 0.5 * u_width / u_half * c.w;
  c.z -= 0.002 * c.w;
  gl_Position = c;
}`;
  const LINE_FS = `#version 300 es
precision highp float; uniform vec3 u_color; out vec4 o; void main() { o = vec4(u_color, 1.0); }`;
  const POINT_VS = `#version 300 es
in vec3 a_pos; in vec3 a_col; uniform mat4 u_mvp; uniform float u_size; out vec3 v_col;
void main() { gl_Position = u_mvp * vec4(a_pos, 1.0); gl_Position.z -= 0.004 * gl_Position.w;
  gl_PointSize = u_size; v_col = a_col; }`;
  const POINT_FS = `#version 300 es
precision highp float; in vec3 v_col; uniform float u_ring; out vec4 o;
void main() { vec2 q = gl_PointCoord * 2.0 - 1.0; float r = dot(q, q); if (r > 1.0) discard;
  o = vec4(r > 0.5 && u_ring > 0.5 ? vec3(0.05) : v_col, 1.0); }`;

  function program(vs, fs) {
    const p = gl.createProgram();
    for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      gl.attachShader(p, s);
    }
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    const u = {};
    const n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; i++) {
      const name = gl.getActiveUniform(p, i).name;
      u[name] = gl.getUniformLocation(p, name);
    }
    const a = {};
    const m = gl.getProgramParameter(p, gl.ACTIVE_ATTRIBUTES);
    for (let i = 0; i < m; i++) {
      const name = gl.getActiveAttrib(p, i).name;
      a[name] = gl.getAttribLocation(p, name);
    }
    return { p, u, a };
  }
  let P = null;
  function initGL() {
    gl = canvas.getContext("webgl2", { antialias: true });
    if (!gl) return false;
    // A software renderer (no GPU) pays twice for multisampling: draw without it there
    // (unless the address ends in #antialias).
    const info = gl.getExtension("WEBGL_debug_renderer_info");
    api.renderer = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
    if (/swiftshader|llvmpipe|software/i.test(api.renderer) && location.hash !== "#antialias") {
      const plain = canvas.cloneNode(false);
      canvas.replaceWith(plain);
      canvas = plain;
      gl = canvas.getContext("webgl2", { antialias: false });
      if (!gl) return false;
    }
    P = {
      surface: program(SURFACE_VS, SURFACE_FS), pick: program(PICK_VS, PICK_FS),
      line: program(LINE_VS, LINE_FS), point: program(POINT_VS, POINT_FS),
    };
    gl.enable(gl.DEPTH_TEST);
    return true;
  }
  function buffer(data, usage) {
    const b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, data, usage || gl.STATIC_DRAW);
    return b;
  }
  function attrib(loc, buf, size) {
    if (loc === undefined || loc < 0) return;
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, size, gl.FLOAT, false, 0, 0);
  }
  function lutTexture(stops) {
    const n = 256, px = new Uint8Array(n * 4);
    for (let i = 0; i < n; i++) {
      const x = (i / (n - 1)) * (stops.length - 1);
      const k = Math.min(Math.floor(x), stops.length - 2), f = x - k;
      for (let c = 0; c < 3; c++) px[i * 4 + c] = Math.round(stops[k][c] + f * (stops[k + 1][c] - stops[k][c]));
      px[i * 4 + 3] = 255;
    }
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, n, 1, 0, gl.RGBA, gl.UNSIGNED_BYTE, px);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return t;
  }
  function imageTexture(url, done) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, 1, 1, 0, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array([200, 200, 200, 255]));
    const img = new Image();
    img.onload = () => {
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, img);
      gl.generateMipmap(gl.TEXTURE_2D);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
      done();
    };
    img.src = url;
    return t;
  }

  // ---------------------------------------------------------------- surfaces
  // A triangle mesh laid out per corner: positions and normals refilled in place when
  // the vertices move; per-corner reference coordinates (UV or a 3D point for the
  // checkerboard), a value per triangle and a flag per vertex.
  class Surface {
    constructor(triangles, nVertices) {
      this.tri = triangles;
      this.m = triangles.length / 3;
      this.n = nVertices;
      this.vn = new Float32Array(nVertices * 3);
      this.cpos = new Float32Array(this.m * 9);
      this.cnrm = new Float32Array(this.m * 9);
      this.pos = null;
      const z3 = new Float32Array(this.m * 9), z1 = new Float32Array(this.m * 3);
      this.b = {
        pos: buffer(this.cpos, gl.DYNAMIC_DRAW), nrm: buffer(this.cnrm, gl.DYNAMIC_DRAW),
        ref: buffer(z3), val: buffer(z1), flag: buffer(z1),
      };
      this.vao = gl.createVertexArray();
      gl.bindVertexArray(this.vao);
      const a = P.surface.a;
      attrib(a.a_pos, this.b.pos, 3); attrib(a.a_nrm, this.b.nrm, 3); attrib(a.a_ref, this.b.ref, 3);
      attrib(a.a_val, this.b.val, 1); attrib(a.a_flag, this.b.flag, 1);
      this.pickVao = gl.createVertexArray();
      gl.bindVertexArray(this.pickVao);
      attrib(P.pick.a.a_pos, this.b.pos, 3);
      gl.bindVertexArray(null);
    }
    // Vertex positions (n × 3); area-weighted vertex normals recomputed.
    setPositions(p, flatNormal) {
      this.pos = p;
      const t = this.tri, vn = this.vn, cp = this.cpos, cn = this.cnrm;
      vn.fill(0);
      for (let f = 0; f < this.m; f++) {
        const a = 3 * t[3 * f], b = 3 * t[3 * f + 1], c = 3 * t[3 * f + 2];
        const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
        const wx = p[c] - p[a], wy = p[c + 1] - p[a + 1], wz = p[c + 2] - p[a + 2];
        const nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
        for (const v of [a, b, c]) { vn[v] += nx; vn[v + 1] += ny; vn[v + 2] += nz; }
      }
      for (let v = 0; v < this.n * 3; v += 3) {
        const l = Math.hypot(vn[v], vn[v + 1], vn[v + 2]);
        if (l > 0) { vn[v] /= l; vn[v + 1] /= l; vn[v + 2] /= l; }
      }
      for (let k = 0; k < this.m * 3; k++) {
        const v = 3 * t[k];
        cp[3 * k] = p[v]; cp[3 * k + 1] = p[v + 1]; cp[3 * k + 2] = p[v + 2];
        if (flatNormal) { cn[3 * k] = 0; cn[3 * k + 1] = 0; cn[3 * k + 2] = 1; }
        else { cn[3 * k] = vn[v]; cn[3 * k + 1] = vn[v + 1]; cn[3 * k + 2] = vn[v + 2]; }
      }
      gl.bindBuffer(gl.ARRAY_BUFFER, this.b.pos); gl.bufferSubData(gl.ARRAY_BUFFER, 0, cp);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.b.nrm); gl.bufferSubData(gl.ARRAY_BUFFER, 0, cn);
    }
    // Reference coordinates of `dim` components, indexed per corner by `index`.
    setRef(coords, index, dim) {
      const r = new Float32Array(this.m * 9);
      for (let k = 0; k < this.m * 3; k++) {
        const i = index[k] * dim;
        for (let c = 0; c < dim; c++) r[3 * k + c] = coords[i + c];
      }
      gl.bindBuffer(gl.ARRAY_BUFFER, this.b.ref); gl.bufferData(gl.ARRAY_BUFFER, r, gl.STATIC_DRAW);
    }
    setTriangleValues(values, map) {
      const v = new Float32Array(this.m * 3);
      for (let f = 0; f < this.m; f++) { const x = values[map ? map[f] : f]; v[3 * f] = x; v[3 * f + 1] = x; v[3 * f + 2] = x; }
      gl.bindBuffer(gl.ARRAY_BUFFER, this.b.val); gl.bufferData(gl.ARRAY_BUFFER, v, gl.STATIC_DRAW);
    }
    setVertexFlags(flags) {
      const v = new Float32Array(this.m * 3);
      for (let k = 0; k < this.m * 3; k++) v[k] = flags[this.tri[k]];
      gl.bindBuffer(gl.ARRAY_BUFFER, this.b.flag); gl.bufferData(gl.ARRAY_BUFFER, v, gl.STATIC_DRAW);
    }
  }

  // Thick line segments: each segment two triangles widened in screen space.
  class Lines {
    constructor(segments) { // Float32Array of (p0, p1) pairs, 6 floats each
      const s = segments.length / 6;
      this.count = s * 6;
      const p0 = new Float32Array(s * 18), p1 = new Float32Array(s * 18), c = new Float32Array(s * 12);
      const corners = [0, -1, 1, -1, 1, 1, 0, -1, 1, 1, 0, 1];
      for (let i = 0; i < s; i++)
        for (let j = 0; j < 6; j++) {
          for (let k = 0; k < 3; k++) { p0[i * 18 + j * 3 + k] = segments[i * 6 + k]; p1[i * 18 + j * 3 + k] = segments[i * 6 + 3 + k]; }
          c[i * 12 + j * 2] = corners[j * 2]; c[i * 12 + j * 2 + 1] = corners[j * 2 + 1];
        }
      this.vao = gl.createVertexArray();
      gl.bindVertexArray(this.vao);
      const a = P.line.a;
      attrib(a.a_p0, buffer(p0), 3); attrib(a.a_p1, buffer(p1), 3); attrib(a.a_corner, buffer(c), 2);
      gl.bindVertexArray(null);
    }
  }

  // Round markers: positions and colours, refilled when they change.
  class Points {
    constructor() {
      this.count = 0;
      this.bp = buffer(new Float32Array(3), gl.DYNAMIC_DRAW);
      this.bc = buffer(new Float32Array(3), gl.DYNAMIC_DRAW);
      this.vao = gl.createVertexArray();
      gl.bindVertexArray(this.vao);
      attrib(P.point.a.a_pos, this.bp, 3); attrib(P.point.a.a_col, this.bc, 3);
      gl.bindVertexArray(null);
    }
    set(positions, colors) {
      this.count = positions.length / 3;
      gl.bindBuffer(gl.ARRAY_BUFFER, this.bp); gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(positions), gl.DYNAMIC_DRAW);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.bc); gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(colors), gl.DYNAMIC_DRAW);
    }
  }

  // Half-edges `3·t + k` as segments between the corners' coordinates.
  function halfEdgeSegments(halfEdges, index, coords, dim) {
    const out = new Float32Array(halfEdges.length * 6);
    for (let i = 0; i < halfEdges.length; i++) {
      const h = halfEdges[i], t = Math.floor(h / 3), k = h % 3;
      const a = index[3 * t + k] * dim, b = index[3 * t + ((k + 1) % 3)] * dim;
      for (let c = 0; c < dim; c++) { out[i * 6 + c] = coords[a + c]; out[i * 6 + 3 + c] = coords[b + c]; }
    }
    return out;
  }

  // ---------------------------------------------------------------- cameras and panels
  // A 3D camera: rotation (rows: right, up, towards the viewer), zoom and pan; shared by
  // panels whose cameras are linked.
  class Camera {
    constructor(axes) { this.axes = axes; this.reset(); }
    // Seen a little from above (0.3 rad), which shows relief better than head-on.
    reset() { this.r = mul3(rot3([1, 0, 0], 0.3), [].concat(...this.axes)); this.zoom = 1; this.pan = [0, 0]; }
    rotate(dx, dy) {
      const up = rot3([0, 1, 0], dx * 0.01), right = rot3([1, 0, 0], dy * 0.01);
      this.r = mul3(right, mul3(up, this.r));
    }
  }
  class Camera2D {
    constructor(lo, hi) { this.lo = lo; this.hi = hi; this.reset(); }
    reset() { this.zoom = 1; this.pan = [0, 0]; }
  }
  const panels = [];
  let pickFbo = null;
  // A panel: part of the canvas (fractions x, w of the width), its camera, what it
  // draws (`draw(mvp, mv, panel)`) and its frame (centre and radius of what it shows).
  function addPanel(name, opts) {
    const p = Object.assign({ name, x: 0, w: 1, items: [], labels: [] }, opts);
    p.background = p.kind === "uv" ? [0.97, 0.97, 0.97] : [0.93, 0.94, 0.96];
    p.label = el("div", { class: "plabel" }, opts.title || name);
    overlay.append(p.label);
    panels.push(p);
    api.panels[name] = p;
    return p;
  }
  function layoutPanels() {
    const W = stage.clientWidth, H = stage.clientHeight, dpr = window.devicePixelRatio || 1;
    canvas.width = Math.max(1, Math.round(W * dpr)); canvas.height = Math.max(1, Math.round(H * dpr));
    canvas.style.width = W + "px"; canvas.style.height = H + "px";
    for (const p of panels) {
      p.px = { x: p.x * W, y: 0, w: p.w * W, h: H };
      p.label.style.left = p.px.x + 8 + "px";
    }
  }
  function matrices(p) {
    const { w, h } = p.px, aspect = w / Math.max(h, 1);
    if (p.kind === "uv") {
      const c = p.camera, lo = c.lo, hi = c.hi;
      const cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]);
      const half = 0.55 * Math.max(hi[0] - lo[0], (hi[1] - lo[1]) * aspect, 1e-12) / c.zoom;
      const sx = 1 / half, sy = aspect / half;
      const mvp = new Float32Array([sx, 0, 0, 0, 0, sy, 0, 0, 0, 0, -0.1, 0,
        -(cx + c.pan[0]) * sx, -(cy + c.pan[1]) * sy, 0, 1]);
      return { mvp, mv: mvp, proj: IDENTITY };
    }
    const f = p.frame(), c = p.camera, r = c.r, s = 1 / f.radius, ce = f.center;
    // model-view: v = R (x − centre) / radius, then moved back by the distance.
    const dist = 1 / Math.sin(Math.PI / 12) / c.zoom;
    const mv = new Float32Array([
      r[0] * s, r[3] * s, r[6] * s, 0, r[1] * s, r[4] * s, r[7] * s, 0, r[2] * s, r[5] * s, r[8] * s, 0, 0, 0, 0, 1]);
    for (let i = 0; i < 3; i++) mv[12 + i] = -(mv[i] * ce[0] + mv[4 + i] * ce[1] + mv[8 + i] * ce[2]);
    mv[12] += c.pan[0]; mv[13] += c.pan[1]; mv[14] -= dist;
    const proj = perspective(Math.PI / 6, aspect, Math.max(dist - 2, 0.01), dist + 2);
    return { mvp: mul(proj, mv), mv, proj };
  }
  // Client (CSS pixel) coordinates of a point of a panel's space, or null behind it.
  function project(p, x) {
    const { mvp } = matrices(p), q = apply(mvp, x), r = canvas.getBoundingClientRect();
    if (q[3] <= 0) return null;
    return { x: r.left + p.px.x + (q[0] * 0.5 + 0.5) * p.px.w, y: r.top + (0.5 - q[1] * 0.5) * p.px.h, depth: q[2] };
  }

  let scheduled = false, animating = null;
  function redraw() {
    if (scheduled) return;
    scheduled = true;
    requestAnimationFrame((time) => {
      scheduled = false;
      if (animating) animating(time);
      draw();
      if (animating) redraw();
    });
  }
  function draw() {
    const dpr = canvas.width / Math.max(stage.clientWidth, 1);
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(1, 1, 1, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.SCISSOR_TEST);
    for (const p of panels) {
      const x = Math.round(p.px.x * dpr), w = Math.round(p.px.w * dpr), h = canvas.height;
      gl.viewport(x, 0, w, h); gl.scissor(x, 0, w, h);
      gl.clearColor(...p.background, 1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      const m = matrices(p);
      for (const item of p.items) if (item.visible === undefined || item.visible()) item.draw(m, { w, h });
      for (const l of p.labels) placeLabel(p, l);
    }
    gl.disable(gl.SCISSOR_TEST);
    api.frames++;
    if (api.firstFrameMs === null) {
      const px = new Uint8Array(4);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px); // waits for the frame
      api.firstFrameMs = performance.now();
    }
  }
  function placeLabel(p, l) {
    const q = project(p, l.at());
    if (!q) { l.el.style.display = "none"; return; }
    const r = canvas.getBoundingClientRect();
    l.el.style.display = "";
    l.el.style.left = q.x - r.left + 6 + "px"; l.el.style.top = q.y - r.top - 18 + "px";
  }

  // Draw items.
  function surfaceItem(surface, style) {
    return {
      visible: style.visible,
      draw(m) {
        const u = P.surface.u, st = typeof style.get === "function" ? style.get() : style;
        gl.useProgram(P.surface.p);
        gl.uniformMatrix4fv(u.u_proj, false, m.proj); gl.uniformMatrix4fv(u.u_mv, false, m.mv);
        gl.uniform1f(u.u_bias, st.bias || 0);
        gl.uniform1i(u.u_mode, st.mode || 0);
        gl.uniform1f(u.u_cells, st.cells || 1);
        gl.uniform2fv(u.u_origin, st.origin || [0, 0]);
        gl.uniform3fv(u.u_scale, st.scale || [0, 1, 0]);
        gl.uniform3fv(u.u_color, st.color || [0.78, 0.78, 0.8]);
        gl.uniform1f(u.u_light, st.light === false ? 0 : 1);
        gl.uniformMatrix4fv(u.u_checker, false, st.checker || new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]));
        gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, st.lut || null); gl.uniform1i(u.u_lut, 0);
        gl.activeTexture(gl.TEXTURE1); gl.bindTexture(gl.TEXTURE_2D, st.tex || null); gl.uniform1i(u.u_tex, 1);
        gl.bindVertexArray(surface.vao);
        gl.drawArrays(gl.TRIANGLES, 0, surface.m * 3);
        gl.bindVertexArray(null);
      },
    };
  }
  function linesItem(lines, color, width, visible) {
    return {
      visible,
      draw(m, vp) {
        if (!lines.count) return;
        const u = P.line.u, dpr = window.devicePixelRatio || 1;
        gl.useProgram(P.line.p);
        gl.uniformMatrix4fv(u.u_mvp, false, m.mvp);
        gl.uniform2f(u.u_half, vp.w / 2, vp.h / 2);
        gl.uniform1f(u.u_width, width * dpr);
        gl.uniform3fv(u.u_color, color);
        gl.bindVertexArray(lines.vao);
        gl.drawArrays(gl.TRIANGLES, 0, lines.count);
        gl.bindVertexArray(null);
      },
    };
  }
  function pointsItem(points, size, onTop, visible) {
    return {
      visible,
      draw(m) {
        if (!points.count) return;
        const u = P.point.u;
        gl.useProgram(P.point.p);
        gl.uniformMatrix4fv(u.u_mvp, false, m.mvp);
        gl.uniform1f(u.u_size, size * (window.devicePixelRatio || 1));
        gl.uniform1f(u.u_ring, size > 6 ? 1 : 0);
        if (onTop) gl.disable(gl.DEPTH_TEST);
        gl.bindVertexArray(points.vao);
        gl.drawArrays(gl.POINTS, 0, points.count);
        gl.bindVertexArray(null);
        gl.enable(gl.DEPTH_TEST);
      },
    };
  }

  // The triangle under a client point of a panel (its surface drawn into an id buffer),
  // or -1.
  function pickTriangle(p, surface, clientX, clientY) {
    const dpr = canvas.width / Math.max(stage.clientWidth, 1);
    const w = canvas.width, h = canvas.height;
    if (!pickFbo || pickFbo.w !== w || pickFbo.h !== h) {
      const fb = gl.createFramebuffer(), tex = gl.createTexture(), depth = gl.createRenderbuffer();
      gl.bindTexture(gl.TEXTURE_2D, tex);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, w, h, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
      gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, w, h);
      gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
      pickFbo = { fb, w, h };
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, pickFbo.fb);
    const x = Math.round(p.px.x * dpr), pw = Math.round(p.px.w * dpr);
    gl.viewport(x, 0, pw, h);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.useProgram(P.pick.p);
    gl.uniformMatrix4fv(P.pick.u.u_mvp, false, matrices(p).mvp);
    gl.bindVertexArray(surface.pickVao);
    gl.drawArrays(gl.TRIANGLES, 0, surface.m * 3);
    gl.bindVertexArray(null);
    const r = canvas.getBoundingClientRect();
    const px = new Uint8Array(4);
    gl.readPixels(Math.floor((clientX - r.left) * dpr), Math.floor(h - (clientY - r.top) * dpr), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return px[0] + px[1] * 256 + px[2] * 65536 + px[3] * 16777216 - 1;
  }

  // Mouse: drag turns (3D) or moves (UV, or with shift / right button), wheel zooms,
  // double-click resets, a click without a drag picks.
  function panelAt(clientX) {
    const r = canvas.getBoundingClientRect(), x = clientX - r.left;
    return panels.find((p) => x >= p.px.x && x < p.px.x + p.px.w);
  }
  function installMouse() {
    let drag = null;
    canvas.addEventListener("contextmenu", (e) => e.preventDefault());
    canvas.addEventListener("pointerdown", (e) => {
      const p = panelAt(e.clientX);
      if (!p) return;
      drag = { p, x: e.clientX, y: e.clientY, x0: e.clientX, y0: e.clientY, pan: e.shiftKey || e.button === 2 || p.kind === "uv" };
      canvas.setPointerCapture(e.pointerId);
    });
    canvas.addEventListener("pointermove", (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX; drag.y = e.clientY;
      const c = drag.p.camera;
      if (drag.pan) {
        if (drag.p.kind === "uv") {
          const { mvp } = matrices(drag.p);
          c.pan[0] -= (2 * dx) / drag.p.px.w / mvp[0]; c.pan[1] += (2 * dy) / drag.p.px.h / mvp[5];
        } else {
          const k = (2 * Math.tan(Math.PI / 12) / Math.sin(Math.PI / 12)) / c.zoom / drag.p.px.h;
          c.pan[0] += dx * k; c.pan[1] -= dy * k;
        }
      } else c.rotate(dx, dy);
      redraw();
    });
    canvas.addEventListener("pointerup", (e) => {
      if (!drag) return;
      const moved = Math.hypot(e.clientX - drag.x0, e.clientY - drag.y0);
      const p = drag.p;
      drag = null;
      if (moved < 4 && p.onPick) { p.onPick(e.clientX, e.clientY); redraw(); }
    });
    canvas.addEventListener("wheel", (e) => {
      const p = panelAt(e.clientX);
      if (!p) return;
      e.preventDefault();
      p.camera.zoom *= Math.exp(-e.deltaY * 0.0015);
      redraw();
    }, { passive: false });
    canvas.addEventListener("dblclick", (e) => {
      const p = panelAt(e.clientX);
      if (!p) return;
      p.camera.reset();
      redraw();
    });
    window.addEventListener("resize", () => { layoutPanels(); redraw(); });
  }

  // ---------------------------------------------------------------- legend
  function legend(panelEl) {
    const box = el("div", { class: "legend" });
    const bar = el("canvas", { width: 256, height: 14 });
    const ticks = el("div", { class: "ticks" }), text = el("div", { class: "ltext" });
    box.append(el("div", { class: "ltitle" }), bar, ticks, text);
    panelEl.append(box);
    return {
      box,
      show(m, stops, full) {
        box.style.display = "";
        box.querySelector(".ltitle").textContent = m.label + (m.log ? " (log scale)" : "");
        const c = bar.getContext("2d");
        for (let i = 0; i < 256; i++) {
          const x = (i / 255) * (stops.length - 1), k = Math.min(Math.floor(x), stops.length - 2), f = x - k;
          const rgb = [0, 1, 2].map((j) => Math.round(stops[k][j] + f * (stops[k + 1][j] - stops[k][j])));
          c.fillStyle = `rgb(${rgb})`; c.fillRect(i, 0, 1, 14);
        }
        const lo = full ? m.min : m.lo, hi = full ? m.max : m.hi;
        const mid = m.log ? Math.sqrt(lo * hi) : 0.5 * (lo + hi);
        ticks.replaceChildren(el("span", {}, fmt(lo)), el("span", {}, fmt(mid)), el("span", {}, fmt(hi)));
        const parts = [`values ${fmt(m.min)} … ${fmt(m.max)} over ${m.count} triangles`];
        const below = full ? 0 : m.below, above = full ? 0 : m.above;
        if (below || above) {
          const pct = (k) => ((100 * k) / m.count).toPrecision(2) + " %";
          const c = [];
          if (below) c.push(`${below} (${pct(below)}) below ${fmt(lo)}`);
          if (above) c.push(`${above} (${pct(above)}) above ${fmt(hi)}`);
          parts.push(`clips: ${c.join(", ")} drawn in the end colours`);
        } else parts.push("does not clip");
        if (m.left_out) parts.push(`${m.left_out} degenerate triangles in grey`);
        text.textContent = parts.join("; ");
      },
      hide() { box.style.display = "none"; },
    };
  }

  // ---------------------------------------------------------------- pages
  function boundsOf(coords, dim) {
    const lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    for (let i = 0; i < coords.length; i += dim)
      for (let c = 0; c < 2; c++) { lo[c] = Math.min(lo[c], coords[i + c]); hi[c] = Math.max(hi[c], coords[i + c]); }
    return { lo, hi };
  }
  function select(id, label, options, onChange) {
    const s = el("select", { id });
    for (const [value, text] of options) s.append(el("option", { value }, text));
    s.addEventListener("change", () => { onChange(s.value); redraw(); });
    return el("label", { class: "row" }, label, s);
  }
  function checkbox(id, label, checked, onChange) {
    const c = el("input", { type: "checkbox", id });
    c.checked = checked;
    c.addEventListener("change", () => { onChange(c.checked); redraw(); });
    return el("label", { class: "row" }, c, " " + label);
  }
  function slider(id, label, value, onInput) {
    const s = el("input", { type: "range", id, min: 0, max: 1, step: 0.001, value });
    const out = el("span", { class: "val" }, Number(value).toFixed(2));
    s.addEventListener("input", () => { out.textContent = Number(s.value).toFixed(2); onInput(Number(s.value)); redraw(); });
    return { row: el("label", { class: "row slider" }, label, s, out), input: s, out };
  }
  function colormaps() {
    const maps = {};
    for (const [k, stops] of Object.entries(DATA.colormaps || {})) maps[k] = { stops, tex: lutTexture(stops) };
    return maps;
  }

  function flatteningPage() {
    const S = DATA.surface, tri = arr(S.triangles), pos = arr(S.positions);
    const hasUv = !!arr("uv.coords");
    const cam = new Camera(S.camera.axes);
    const frame = () => ({ center: S.camera.center, radius: S.camera.radius });
    const p3 = addPanel("surface", { kind: "3d", x: 0, w: hasUv ? 0.5 : 1, camera: cam, frame, title: "surface (3D)" });
    const surf = new Surface(tri, pos.length / 3);
    surf.setPositions(pos);
    const state = { mode: "checker", full: false, seams: true };
    const maps = colormaps();
    let texture = null;
    if (DATA.texture) texture = imageTexture(DATA.texture, redraw);
    const style = { get: () => styleFor(false) };
    let uvBounds = null, cells = 1;
    const measures = DATA.measures || [];
    function styleFor(flat) {
      const s = { light: !flat };
      if (state.mode === "checker") Object.assign(s, { mode: 1, cells, origin: uvBounds ? uvBounds.lo : [0, 0] });
      else if (state.mode === "texture") Object.assign(s, { mode: 4, tex: texture });
      else if (state.mode === "plain") s.mode = 0;
      else {
        const m = measures.find((x) => x.key === state.mode);
        Object.assign(s, { mode: 3, lut: maps[m.map].tex, scale: [state.full ? m.min : m.lo, state.full ? m.max : m.hi, m.log ? 1 : 0] });
      }
      return s;
    }
    p3.items.push(surfaceItem(surf, style));
    const legends = [];
    let flatSurface = null;
    if (hasUv) {
      const uv = arr("uv.coords"), uvTri = arr("uv.triangles");
      uvBounds = boundsOf(uv, 2);
      cells = 16 / Math.max(uvBounds.hi[0] - uvBounds.lo[0], uvBounds.hi[1] - uvBounds.lo[1], 1e-12);
      surf.setRef(uv, uvTri, 2);
      const uv3 = new Float32Array((uv.length / 2) * 3);
      for (let i = 0; i < uv.length / 2; i++) { uv3[3 * i] = uv[2 * i]; uv3[3 * i + 1] = uv[2 * i + 1]; }
      const flat = new Surface(uvTri, uv.length / 2);
      flat.setPositions(uv3, true);
      flat.setRef(uv, uvTri, 2);
      flatSurface = flat;
      const pUv = addPanel("uv", { kind: "uv", x: 0.5, w: 0.5, camera: new Camera2D(uvBounds.lo, uvBounds.hi), title: "UV layout" });
      pUv.items.push(surfaceItem(flat, { get: () => styleFor(true) }));
      const seams = arr("surface.seams"), boundary = arr("surface.boundary");
      const bUv = new Lines(halfEdgeSegments(boundary, tri, pos, 3));
      const seam3 = new Lines(halfEdgeSegments(seams, tri, pos, 3));
      const seamUv = new Lines(halfEdgeSegments(seams, uvTri, uv3, 3));
      const boundaryUv = new Lines(halfEdgeSegments(boundary, uvTri, uv3, 3));
      const on = () => state.seams;
      p3.items.push(linesItem(seam3, [0.85, 0.1, 0.1], 2.5, on), linesItem(bUv, [0.15, 0.15, 0.15], 1.5, on));
      pUv.items.push(linesItem(seamUv, [0.85, 0.1, 0.1], 2.5, on), linesItem(boundaryUv, [0.15, 0.15, 0.15], 1.2, on));
      for (const m of measures) {
        const values = arr(m.array);
        m.values = values;
      }
      legends.push(legend(overlay));
    } else {
      const boundary = arr("surface.boundary");
      p3.items.push(linesItem(new Lines(halfEdgeSegments(boundary, tri, pos, 3)), [0.15, 0.15, 0.15], 1.5, () => state.seams));
    }
    function applyMode() {
      const m = measures.find((x) => x.key === state.mode);
      if (m) {
        surf.setTriangleValues(m.values);
        if (flatSurface) flatSurface.setTriangleValues(m.values);
        legends.forEach((l) => l.show(m, maps[m.map].stops, state.full));
      } else legends.forEach((l) => l.hide());
    }
    const options = [["checker", "checkerboard of the UVs"]];
    if (texture) options.push(["texture", "texture"]);
    for (const m of measures) options.push([m.key, m.label]);
    options.push(["plain", "plain (shading only)"]);
    if (!hasUv) options.length = 0, options.push(["plain", "plain (shading only)"]), state.mode = "plain";
    section("Show",
      select("colour", "colour by ", options, (v) => { state.mode = v; applyMode(); }),
      measures.length ? checkbox("full-range", "full range (no clipping)", false, (v) => { state.full = v; applyMode(); }) : null,
      checkbox("seams", hasUv ? "seams (red) and boundary" : "boundary", true, (v) => { state.seams = v; }));
    numbersTable(DATA.numbers, DATA.report_source);
    notes();
    help(["drag: turn the surface (shift-drag or right-drag: move)", "wheel: zoom", "double-click: reset the view",
      "UV layout: drag moves, wheel zooms"]);
    api.setMode = (v) => { state.mode = v; document.getElementById("colour").value = v; applyMode(); redraw(); };
    return { applyMode };
  }

  // The planar checkerboard of a surface: coordinates (x − centre)·axes / cell in its
  // camera frame (right, up), so that it is seen square from the first view.
  function checkerMatrix(ax, c0, cell) {
    const s = 1 / cell;
    const m = new Float32Array([ax[0][0] * s, ax[1][0] * s, ax[2][0] * s, 0, ax[0][1] * s, ax[1][1] * s, ax[2][1] * s, 0,
      ax[0][2] * s, ax[1][2] * s, ax[2][2] * s, 0, 0, 0, 0, 1]);
    for (let i = 0; i < 3; i++) m[12 + i] = -(m[i] * c0[0] + m[4 + i] * c0[1] + m[8 + i] * c0[2]);
    return m;
  }

  function matchPage() {
    const A = DATA.a, B = DATA.b;
    const aPos = arr(A.positions), aTri = arr(A.triangles), bPos = arr(B.positions), bTri = arr(B.triangles);
    const corrT = arr("corr.triangle"), corrB = arr("corr.barycentric"), disp = arr("morph.displacements");
    const na = aPos.length / 3;
    const cam = new Camera(A.camera.axes);
    const state = { t: 0, carried: true, unmatched: true, checker: true };
    const lerp = (a, b, t) => a.map((x, i) => x + t * (b[i] - x));
    const frameA = () => ({ center: lerp(A.camera.center, B.camera.center, state.t), radius: A.camera.radius + state.t * (B.camera.radius - A.camera.radius) });
    const frameB = () => ({ center: B.camera.center, radius: B.camera.radius });
    const pa = addPanel("a", { kind: "3d", x: 0, w: 0.5, camera: cam, frame: frameA, title: "A" });
    const pb = addPanel("b", { kind: "3d", x: 0.5, w: 0.5, camera: cam, frame: frameB, title: "B" });
    // The checkerboard of A: its own frame, carried along by the reference coordinates.
    const checker = checkerMatrix(DATA.checker.axes, DATA.checker.center, DATA.checker.cell);
    const unmatched = new Float32Array(na);
    for (let v = 0; v < na; v++) unmatched[v] = corrT[v] < 0 ? 1 : 0;
    const current = new Float32Array(aPos.length);
    function morph() {
      for (let i = 0; i < aPos.length; i++) current[i] = aPos[i] + state.t * disp[i];
      surfA.setPositions(current);
    }
    const surfA = new Surface(aTri, na);
    surfA.setRef(aPos, aTri, 3);
    surfA.setVertexFlags(unmatched);
    morph();
    const surfB = new Surface(bTri, bPos.length / 3);
    surfB.setPositions(bPos);
    // A's fully matched triangles at their points of B.
    const keep = [];
    for (let f = 0; f < aTri.length / 3; f++)
      if (corrT[aTri[3 * f]] >= 0 && corrT[aTri[3 * f + 1]] >= 0 && corrT[aTri[3 * f + 2]] >= 0) keep.push(aTri[3 * f], aTri[3 * f + 1], aTri[3 * f + 2]);
    const carried = new Surface(new Uint32Array(keep), na);
    const end = new Float32Array(aPos.length);
    for (let i = 0; i < aPos.length; i++) end[i] = aPos[i] + disp[i];
    carried.setPositions(end);
    carried.setRef(aPos, carried.tri, 3);
    pa.items.push(surfaceItem(surfA, { get: () => (state.checker ? { mode: 2, checker } : { mode: 0 }) }));
    pb.items.push(surfaceItem(surfB, { color: [0.72, 0.74, 0.78] }));
    pb.items.push(surfaceItem(carried, { mode: 2, checker, bias: 0.01, visible: () => state.carried }));
    // Unmatched vertices, picks and landmarks as markers.
    const unmatchedPts = new Points();
    const ups = [], ucs = [];
    function unmatchedPoints() {
      ups.length = 0; ucs.length = 0;
      for (let v = 0; v < na; v++) if (corrT[v] < 0) { ups.push(current[3 * v], current[3 * v + 1], current[3 * v + 2]); ucs.push(0.86, 0.08, 0.12); }
      unmatchedPts.set(ups, ucs);
    }
    unmatchedPoints();
    pa.items.push(pointsItem(unmatchedPts, 3, false, () => state.unmatched));
    const pickA = new Points(), pickB = new Points();
    pa.items.push(pointsItem(pickA, 14, true)); pb.items.push(pointsItem(pickB, 14, true));
    function imageOnB(v) {
      const t = corrT[v];
      if (t < 0) return null;
      const p = [0, 0, 0];
      for (let k = 0; k < 3; k++) {
        const w = corrB[3 * v + k], q = 3 * bTri[3 * t + k];
        for (let c = 0; c < 3; c++) p[c] += w * bPos[q + c];
      }
      return p;
    }
    const pickInfo = el("div", { id: "pick-info", class: "small" }, "Click a point of A to see its image on B.");
    function pickVertex(v) {
      const a = [current[3 * v], current[3 * v + 1], current[3 * v + 2]];
      const b = imageOnB(v);
      pickA.set(a, [1, 0.85, 0.1]);
      pickB.set(b || [], b ? [1, 0.85, 0.1] : []);
      api.picked = { vertex: v, a, b, triangle: corrT[v], barycentric: b ? [corrB[3 * v], corrB[3 * v + 1], corrB[3 * v + 2]] : null };
      pickInfo.textContent = b
        ? `vertex ${v} of A → triangle ${corrT[v]} of B at (${b.map((x) => fmt(x)).join(", ")})`
        : `vertex ${v} of A has no counterpart on B (unmatched)`;
      redraw();
    }
    pa.onPick = (x, y) => {
      const f = pickTriangle(pa, surfA, x, y);
      if (f < 0) return;
      // The corner of the triangle nearest the click.
      let best = -1, bestD = Infinity;
      for (let k = 0; k < 3; k++) {
        const v = aTri[3 * f + k], q = project(pa, [current[3 * v], current[3 * v + 1], current[3 * v + 2]]);
        const d = q ? Math.hypot(q.x - x, q.y - y) : Infinity;
        if (d < bestD) { bestD = d; best = v; }
      }
      pickVertex(best);
    };
    // Landmarks: A's on A, B's on B, and where A's land on B.
    if (DATA.landmarks && DATA.landmarks.length) {
      const la = new Points(), lb = new Points();
      const lap = [], lbp = [], lac = [], lbc = [];
      for (const l of DATA.landmarks) {
        const b = [bPos[3 * l.b], bPos[3 * l.b + 1], bPos[3 * l.b + 2]];
        lbp.push(...b); lbc.push(0.1, 0.7, 0.3);
        const img = imageOnB(l.a);
        if (img) { lbp.push(...img); lbc.push(0.1, 0.75, 0.95); }
        pa.labels.push(labelAt(l.name, () => [current[3 * l.a], current[3 * l.a + 1], current[3 * l.a + 2]]));
        pb.labels.push(labelAt(l.name, () => b));
      }
      const laUpdate = () => {
        lap.length = 0; lac.length = 0;
        for (const l of DATA.landmarks) { lap.push(current[3 * l.a], current[3 * l.a + 1], current[3 * l.a + 2]); lac.push(0.1, 0.7, 0.3); }
        la.set(lap, lac);
      };
      laUpdate();
      lb.set(lbp, lbc);
      pa.items.push(pointsItem(la, 9, false)); pb.items.push(pointsItem(lb, 9, false));
      api.landmarksUpdate = laUpdate;
    }
    function labelAt(text, at) {
      const e = el("div", { class: "mlabel" }, text);
      overlay.append(e);
      return { el: e, at };
    }
    // Side panel.
    const conf = DATA.confidence;
    const badge = document.getElementById("badge");
    const verdict = conf && conf.verdict ? conf.verdict : null;
    badge.textContent = verdict ? "confidence: " + verdict : "no confidence verdict recorded";
    badge.className = "badge " + (verdict || "none");
    const ctr = DATA.counts;
    const morphSlider = slider("morph", "morph A → A on B ", 0, (t) => { state.t = t; morph(); unmatchedPoints(); if (api.landmarksUpdate) api.landmarksUpdate(); if (api.picked) pickVertex(api.picked.vertex); });
    let playing = false;
    const play = el("button", { id: "play", onclick: () => {
      playing = !playing; play.textContent = playing ? "pause" : "play";
      let last = null;
      animating = playing ? (time) => {
        if (last !== null) {
          let t = state.t + (time - last) / 2000;
          if (t > 1) t = 0;
          morphSlider.input.value = t; morphSlider.input.dispatchEvent(new Event("input"));
        }
        last = time;
      } : null;
      redraw();
    } }, "play");
    section("Match",
      el("p", { class: "verdict " + (verdict || "none") }, verdict ? `verdict: ${verdict}` : "no confidence verdict in match.json"),
      conf && conf.reasons && conf.reasons.length ? el("ul", { class: "small" }, ...conf.reasons.map((r) => el("li", {}, r))) : null,
      el("p", { class: "small" }, `${ctr.matched} vertices of A matched, ${ctr.unmatched} unmatched (red)`),
      morphSlider.row, el("div", { class: "row" }, play),
      el("p", { class: "small" }, "morph end: " + DATA.morph_source),
      checkbox("checker", "A's checkerboard", true, (v) => { state.checker = v; }),
      checkbox("carried", "A's checkerboard carried onto B", true, (v) => { state.carried = v; }),
      checkbox("unmatched", "unmatched vertices of A", true, (v) => { state.unmatched = v; }),
      pickInfo);
    numbersTable(DATA.numbers, "match.json");
    if (conf && conf.measures) section("Confidence measures", el("table", { class: "numbers" },
      ...Object.entries(conf.measures).map(([k, v]) => el("tr", {}, el("th", {}, k), el("td", {}, fmt(v))))));
    section("Files", el("p", { class: "small" }, `folder ${DATA.files.folder}`), el("p", { class: "small" }, `A ${DATA.files.a}`), el("p", { class: "small" }, `B ${DATA.files.b}`));
    notes();
    help(["drag: turn both surfaces (one camera)", "shift-drag or right-drag: move", "wheel: zoom", "double-click: reset",
      "click on A: its image on B (yellow)", "landmarks: green on their surface, blue where A's land on B"]);
    api.pickVertex = pickVertex;
    api.vertexA = (v) => [current[3 * v], current[3 * v + 1], current[3 * v + 2]];
    api.imageOnB = imageOnB;
  }

  function morphPage() {
    const S = DATA.surface, tri = arr(S.triangles), base = arr(S.positions);
    const cam = new Camera(S.camera.axes);
    const p = addPanel("surface", { kind: "3d", x: 0, w: 1, camera: cam, frame: () => ({ center: S.camera.center, radius: S.camera.radius }), title: DATA.title });
    const surf = new Surface(tri, base.length / 3);
    const targets = (DATA.targets || []).map((t) => ({ name: t.name, d: arr(t.array), w: 0 }));
    const current = new Float32Array(base.length);
    function update() {
      current.set(base);
      for (const t of targets) if (t.w !== 0) for (let i = 0; i < current.length; i++) current[i] += t.w * t.d[i];
      surf.setPositions(current);
    }
    update();
    // Coloured by its texture, or by a checkerboard fixed to the base mesh that follows
    // the targets (it shows how the surface stretches).
    let tex = null;
    const look = { mode: 2, checker: checkerMatrix(S.camera.axes, S.camera.center, S.camera.radius / 8) };
    if (DATA.texture && arr("uv.coords")) {
      tex = imageTexture(DATA.texture, redraw);
      surf.setRef(arr("uv.coords"), tri, 2);
      Object.assign(look, { mode: 4, tex });
    } else surf.setRef(base, tri, 3);
    p.items.push(surfaceItem(surf, look));
    const sliders = targets.map((t, k) => slider("target-" + k, t.name + " ", 0, (w) => { t.w = w; update(); }));
    const anim = DATA.animation;
    const rows = [...sliders.map((s) => s.row)];
    if (anim && anim.times.length) {
      const T = anim.times[anim.times.length - 1] || 1;
      let clock = 0, playing = false, last = null;
      const time = slider("time", "time ", 0, (x) => { clock = x * T; setFromAnimation(); });
      time.input.max = 1;
      function setFromAnimation() {
        const ts = anim.times;
        let k = 0;
        while (k < ts.length - 2 && clock > ts[k + 1]) k++;
        const span = ts[Math.min(k + 1, ts.length - 1)] - ts[k];
        const f = span > 0 ? Math.min(Math.max((clock - ts[k]) / span, 0), 1) : 0;
        targets.forEach((t, j) => {
          const w0 = anim.weights[k][j], w1 = anim.weights[Math.min(k + 1, ts.length - 1)][j];
          t.w = w0 + f * (w1 - w0);
          sliders[j].input.value = t.w; sliders[j].out.textContent = t.w.toFixed(2);
        });
        update();
      }
      const play = el("button", { id: "play", onclick: () => {
        playing = !playing; play.textContent = playing ? "pause" : "play"; last = null;
        animating = playing ? (now) => {
          if (last !== null) { clock = (clock + (now - last) / 1000) % T; time.input.value = clock / T; time.out.textContent = (clock / T).toFixed(2); setFromAnimation(); }
          last = now;
        } : null;
        redraw();
      } }, "play");
      rows.push(el("p", { class: "small" }, `animation "${anim.name}": ${anim.times.length} keyframes over ${fmt(T)} s`), time.row, el("div", { class: "row" }, play));
    }
    section(targets.length === 1 ? "Morph" : "Morph targets", ...rows);
    section("Mesh", el("p", { class: "small" }, `${S.vertices} vertices, ${S.triangle_count} triangles, ${targets.length} targets`));
    notes();
    help(["sliders: one weight per target", "play: the file's animation", "drag: turn (shift-drag: move)", "wheel: zoom", "double-click: reset"]);
  }

  function tablePage() {
    stage.style.display = "none";
    document.getElementById("main").classList.add("tablemain");
    const cols = DATA.columns, rows = DATA.rows.map((r, i) => ({ r, i }));
    const table = el("table", { class: "summary", id: "summary" });
    const head = el("tr", {}, el("th", {}, "page"));
    let sortKey = -1, sortDir = 1;
    cols.forEach((c, j) => head.append(el("th", { class: "sortable", onclick: () => { sortDir = sortKey === j ? -sortDir : 1; sortKey = j; fill(); } }, c)));
    head.append(el("th", {}, "notes"));
    const body = el("tbody");
    table.append(el("thead", {}, head), body);
    function cell(v, c) {
      const cls = (c === "status" || c === "verdict") && typeof v === "string" ? "tag " + v : "";
      return el("td", { class: cls, title: v === null ? "" : String(v) }, fmt(v));
    }
    function fill() {
      const sorted = rows.slice();
      if (sortKey >= 0) sorted.sort((x, y) => {
        const a = x.r[sortKey], b = y.r[sortKey];
        if (a === b) return 0; if (a === null) return 1; if (b === null) return -1;
        return (a < b ? -1 : 1) * sortDir;
      });
      body.replaceChildren(...sorted.map(({ r, i }) => {
        const link = DATA.links[i];
        return el("tr", {}, el("td", {}, link ? el("a", { href: link }, "open") : "–"), ...r.map((v, j) => cell(v, cols[j])), el("td", { class: "small" }, DATA.item_notes[i] || ""));
      }));
    }
    fill();
    const wrap = el("div", { class: "tablewrap" }, el("p", { class: "small" }, `${rows.length} items from ${DATA.source}; click a column to sort; "open" shows an item's own page.`), table);
    document.getElementById("main").append(wrap);
    side.style.display = "none";
  }

  // ---------------------------------------------------------------- start
  function start() {
    const t0 = performance.now();
    document.getElementById("title").textContent = DATA.title;
    document.title = DATA.title;
    if (DATA.kind === "table") { tablePage(); api.decodeMs = performance.now() - t0; api.ready = true; return; }
    if (!initGL()) {
      stage.append(el("p", { class: "nogl" }, "This page needs WebGL2, which this browser does not offer."));
      api.ready = true; return;
    }
    let page = null;
    if (DATA.kind === "flattening") page = flatteningPage();
    else if (DATA.kind === "match") matchPage();
    else if (DATA.kind === "morph") morphPage();
    document.getElementById("hint").textContent = "drag to turn · wheel to zoom · double-click to reset";
    layoutPanels();
    installMouse();
    if (page) page.applyMode();
    api.decodeMs = performance.now() - t0;
    draw();
    api.ready = true;
  }

  // For tests and scripts: where a point of a panel is on the screen, and the pixels.
  api.project = (name, x) => project(api.panels[name], x);
  api.render = () => { draw(); };
  api.pixelAt = (clientX, clientY) => {
    draw();
    const r = canvas.getBoundingClientRect(), dpr = canvas.width / Math.max(stage.clientWidth, 1), px = new Uint8Array(4);
    gl.readPixels(Math.floor((clientX - r.left) * dpr), Math.floor(canvas.height - (clientY - r.top) * dpr), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    return Array.from(px);
  };
  // A summary of the canvas: the fraction of each panel's pixels that differ from its
  // background, and a hash of all pixels.
  api.snapshot = () => {
    draw();
    const w = canvas.width, h = canvas.height, px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let hash = 2166136261;
    for (let i = 0; i < px.length; i += 4)
      hash = Math.imul(hash ^ (px[i] | (px[i + 1] << 8) | (px[i + 2] << 16)), 16777619) >>> 0;
    const dpr = w / Math.max(stage.clientWidth, 1), panelsDrawn = {};
    let drawn = 0;
    for (const p of panels) {
      const bg = p.background.map((c) => Math.round(c * 255));
      const x0 = Math.round(p.px.x * dpr), x1 = Math.round((p.px.x + p.px.w) * dpr);
      let n = 0;
      for (let y = 0; y < h; y++)
        for (let x = x0; x < x1; x++) {
          const i = 4 * (y * w + x);
          if (Math.abs(px[i] - bg[0]) > 1 || Math.abs(px[i + 1] - bg[1]) > 1 || Math.abs(px[i + 2] - bg[2]) > 1) n++;
        }
      panelsDrawn[p.name] = n / Math.max((x1 - x0) * h, 1);
      drawn += n;
    }
    return { width: w, height: h, drawnFraction: drawn / (w * h), panels: panelsDrawn, hash };
  };
  try { start(); } catch (e) {
    api.errors.push(String(e && e.stack || e));
    stage.append(el("pre", { class: "nogl" }, "The viewer failed: " + String(e && e.message || e)));
    throw e;
  }
})();

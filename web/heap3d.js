// A 3D heap a person can turn: every grain a sphere drawn as a shaded
// WebGL point sprite, coloured by height. Drag (or the arrow keys) to
// turn it, the wheel (or + and −) to zoom. No library: one vertex and one
// fragment shader.
"use strict";

(function () {
  const VERTEX = `
    attribute vec3 a_pos;
    attribute float a_radius;
    uniform mat3 u_turn;
    uniform vec3 u_centre;
    uniform float u_inv_size;
    uniform float u_zoom;
    uniform float u_aspect;
    uniform float u_pixels;
    uniform float u_top;
    varying float v_height;
    void main() {
      vec3 p = u_turn * ((a_pos - u_centre) * u_inv_size);
      gl_Position = vec4(p.x * u_zoom / u_aspect, p.y * u_zoom, p.z * 0.4, 1.0);
      gl_PointSize = 2.0 * a_radius * u_inv_size * u_zoom * u_pixels;
      v_height = clamp(a_pos.z / u_top, 0.0, 1.0);
    }`;
  const FRAGMENT = `
    precision mediump float;
    varying float v_height;
    void main() {
      vec2 c = gl_PointCoord * 2.0 - 1.0;
      float r2 = dot(c, c);
      if (r2 > 1.0) discard;
      vec3 n = vec3(c.x, -c.y, sqrt(1.0 - r2));
      float light = 0.3 + 0.7 * max(dot(n, normalize(vec3(0.4, 0.6, 0.7))), 0.0);
      vec3 low = vec3(0.14, 0.34, 0.71);
      vec3 high = vec3(0.86, 0.56, 0.18);
      gl_FragColor = vec4(mix(low, high, v_height) * light, 1.0);
    }`;

  function shader(gl, type, source) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }

  function program(gl) {
    const p = gl.createProgram();
    gl.attachShader(p, shader(gl, gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(p, shader(gl, gl.FRAGMENT_SHADER, FRAGMENT));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  }

  // The turn: yaw about the vertical (z) axis, then the view looks along
  // the turned y axis with z up, tilted by `pitch` about the screen's x axis.
  function turn(yaw, pitch) {
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    // rows of the matrix taking world to screen (x right, y up, z depth)
    const r = [
      [cy, -sy, 0],
      [-sp * sy, -sp * cy, cp],
      [cp * sy, cp * cy, sp],
    ];
    // column-major for WebGL
    return new Float32Array([r[0][0], r[1][0], r[2][0], r[0][1], r[1][1], r[2][1], r[0][2], r[1][2], r[2][2]]);
  }

  // Draws `grains` ([{position: [x, y, z], radius}]) into `canvas`; returns
  // the canvas, or null without WebGL.
  function viewer(canvas, grains) {
    const gl = canvas.getContext("webgl", { antialias: true, preserveDrawingBuffer: true });
    if (!gl || grains.length === 0) return null;
    const prog = program(gl);
    const pos = new Float32Array(grains.length * 3);
    const rad = new Float32Array(grains.length);
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    grains.forEach((g, i) => {
      for (let a = 0; a < 3; a++) {
        pos[3 * i + a] = g.position[a];
        lo[a] = Math.min(lo[a], g.position[a] - g.radius);
        hi[a] = Math.max(hi[a], g.position[a] + g.radius);
      }
      rad[i] = g.radius;
    });
    const centre = lo.map((v, a) => 0.5 * (v + hi[a]));
    const size = 0.5 * Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    const buffer = (data, name, n) => {
      const b = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
      const at = gl.getAttribLocation(prog, name);
      gl.enableVertexAttribArray(at);
      gl.vertexAttribPointer(at, n, gl.FLOAT, false, 0, 0);
    };
    gl.useProgram(prog);
    buffer(pos, "a_pos", 3);
    buffer(rad, "a_radius", 1);
    const u = name => gl.getUniformLocation(prog, name);
    const state = { yaw: 0.6, pitch: 0.35, zoom: 0.8 };
    function draw() {
      gl.viewport(0, 0, canvas.width, canvas.height);
      gl.clearColor(1, 1, 1, 1);
      gl.enable(gl.DEPTH_TEST);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.uniformMatrix3fv(u("u_turn"), false, turn(state.yaw, state.pitch));
      gl.uniform3fv(u("u_centre"), centre);
      gl.uniform1f(u("u_inv_size"), 1 / size);
      gl.uniform1f(u("u_zoom"), state.zoom);
      gl.uniform1f(u("u_aspect"), canvas.width / canvas.height);
      gl.uniform1f(u("u_pixels"), 0.5 * canvas.height);
      gl.uniform1f(u("u_top"), Math.max(hi[2], 1e-30));
      gl.drawArrays(gl.POINTS, 0, grains.length);
      canvas.dataset.drawn = String(grains.length);
      canvas.dataset.yaw = state.yaw.toFixed(3);
    }
    let drag = null;
    canvas.addEventListener("pointerdown", e => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener("pointerup", () => { drag = null; });
    canvas.addEventListener("pointermove", e => {
      if (!drag) return;
      state.yaw += 0.01 * (e.clientX - drag[0]);
      state.pitch = Math.max(-1.5, Math.min(1.5, state.pitch + 0.01 * (e.clientY - drag[1])));
      drag = [e.clientX, e.clientY];
      draw();
    });
    canvas.addEventListener("wheel", e => {
      e.preventDefault();
      state.zoom = Math.max(0.2, Math.min(8, state.zoom * Math.exp(-0.001 * e.deltaY)));
      draw();
    }, { passive: false });
    canvas.addEventListener("keydown", e => {
      const step = { ArrowLeft: [-0.1, 0], ArrowRight: [0.1, 0], ArrowUp: [0, -0.1], ArrowDown: [0, 0.1] }[e.key];
      if (step) { state.yaw += step[0]; state.pitch = Math.max(-1.5, Math.min(1.5, state.pitch + step[1])); }
      else if (e.key === "+" || e.key === "=") state.zoom *= 1.1;
      else if (e.key === "-") state.zoom /= 1.1;
      else return;
      e.preventDefault();
      draw();
    });
    draw();
    return canvas;
  }

  window.heap3d = { viewer };
})();

// The page of a walkvis web export: loads walkvis.bin (walkvis-data.js from file://, where browsers
// refuse fetch), then each view cell's tree when an eye needs it (cellLoader), draws with WebGL2 what walkthrough/scene_drawer.cpp draws (the same shaders, eye-
// relative float positions, depth test off, fragments in the frame's order), walks by viewer.js.
//
// URL: ?frame=K (key K of the stored tour) or ?eye=x,y,z&yaw=Y&pitch=P draws one view and sets
// body[data-drawn]; &size=WxH (default 640x480), &ids=1 (fragment index + 1 as RGB), &wire=1,
// &rejected=1, &overlay=1, &cells=none (no cell fetched: the BSP order), &prefetch=0. ?bench=K draws tour keys 0..K-1 &reps=R times in four runs (the floor,
// the z-buffer, the BSP order, the HFD order) and writes their medians, split into order, GL calls
// and the wait for the rasteriser, into body[data-bench]. Otherwise: the walkthrough, WASD, Shift,
// mouse look (click).
'use strict';

(function () {
  const W = window.walkvis;
  const scriptMs = performance.now();  // this script starts: the document and viewer.js are in
  const params = new URLSearchParams(location.search);
  const canvas = document.getElementById('view');
  const overlayEl = document.getElementById('overlay');
  const messageEl = document.getElementById('message');

  function showError(text) {
    messageEl.textContent = text;
    messageEl.style.display = 'block';
    overlayEl.style.display = 'none';
    document.body.dataset.error = text;
    document.title = 'walkvis: error';
  }

  function decodeBase64(text) {
    // Native where there is one: 45 MB in 0.25 s against 0.48-0.56 s for atob's loop (Chromium 156).
    if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text).buffer;
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return bytes.buffer;
  }

  // The bytes of an export file: fetched from a server; from file://, where browsers refuse fetch,
  // its script form run, which hands them over in base64 to the function `handOver` installs.
  function fileBytes(file, script, handOver) {
    if (location.protocol !== 'file:') {
      return fetch(file).then((r) => {
        if (!r.ok) throw new W.ExportError(file + ': ' + r.status + ' ' + r.statusText);
        return r.arrayBuffer();
      });
    }
    return new Promise((resolve, reject) => {
      let done = false;
      handOver((text) => {
        done = true;
        try {
          resolve(decodeBase64(text));
        } catch (e) {
          reject(new W.ExportError(script + ': not base64 (' + e.message + ')'));
        }
      });
      const s = document.createElement('script');
      s.src = script;
      s.onerror = () => reject(new W.ExportError(script + ': missing or unreadable beside index.html'));
      s.onload = () => {
        if (!done) reject(new W.ExportError(script + ': truncated or malformed (it did not hand over the data)'));
      };
      document.head.appendChild(s);
    });
  }

  // ---- view cells ---------------------------------------------------------------------------
  // Each view cell's tree is a file of its own (cells/K.bin from a server, cells/K.js from file://),
  // fetched when an eye first needs it and handed to the scene by W.attachCell; until it is in, a
  // frame there takes the BSP order (W.frameOrder). Each cell is fetched at most once; the order
  // they came in is body[data-cells-loaded]. A cell that cannot be read stops the page with its
  // message (onError).
  function cellLoader(scene, onError) {
    const pending = new Map();  // cell index → promise of the cell
    const handOvers = new Map();  // cell index → what takes its file:// script's data
    const loaded = [];
    window.walkvisCell = (k, text) => { if (handOvers.has(k)) handOvers.get(k)(text); };
    const bytes = (cell) =>
      fileBytes(cell.file, 'cells/' + cell.index + '.js', (take) => handOvers.set(cell.index, take));
    const load = (cell) => {
      let p = pending.get(cell.index);
      if (!p) {
        p = bytes(cell).then((buffer) => W.attachCell(scene, cell.index, buffer)).then((c) => {
          loaded.push(c.index);
          document.body.dataset.cellsLoaded = loaded.join(',');
          return c;
        });
        p.catch(onError);
        pending.set(cell.index, p);
      }
      return p;
    };
    // The cells not yet asked for, one at a time, the nearest to `eye()` first (its own level's
    // before the others): a walker usually finds the next cell in when it gets there.
    const prefetch = (eye) => {
      const rest = scene.cells.filter((c) => !pending.has(c.index));
      if (rest.length === 0) return;
      const e = eye(), l = W.levelAt(scene, e);
      const far = (c) => c.box ? Math.hypot(0.5 * (c.box[0] + c.box[2]) - e[0], 0.5 * (c.box[1] + c.box[3]) - e[2]) : 0;
      rest.sort((a, b) => (a.level !== l) - (b.level !== l) || far(a) - far(b));
      load(rest[0]).then(() => prefetch(eye), () => {});
    };
    return { load, prefetch };
  }

  // ---- drawing ------------------------------------------------------------------------------
  const kVertex = `#version 300 es
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 color;
layout(location = 2) in uint id;
layout(location = 3) in vec3 normal;
uniform mat4 clip;
out vec3 v_pos;
flat out vec3 v_color;
flat out uint v_id;
flat out vec3 v_normal;
void main() {
  gl_Position = clip * vec4(pos, 1.0);
  v_pos = pos;
  v_color = color;
  v_id = id;
  v_normal = normal;
}`;
  const kFragment = `#version 300 es
precision highp float;
precision highp int;
in vec3 v_pos;
flat in vec3 v_color;
flat in uint v_id;
flat in vec3 v_normal;
uniform int style;
uniform int marker;
out vec4 o_color;
void main() {
  if (style == 1) {
    o_color = vec4(float(v_id & 255u), float((v_id >> 8u) & 255u), float((v_id >> 16u) & 255u), 255.0) / 255.0;
  } else if (marker == 1) {
    o_color = vec4(1.0, 0.0, 1.0, 1.0);
  } else {
    float l = abs(dot(v_normal, normalize(-v_pos)));
    o_color = vec4(v_color * (0.3 + 0.7 * l), 1.0);
  }
}`;

  class Renderer {
    constructor(gl, scene) {
      this.gl = gl;
      this.scene = scene;
      const n = scene.meta.fragments, nv = scene.meta.vertices;
      const colors = new Uint8Array(4 * nv), ids = new Uint32Array(nv), normals = new Float32Array(3 * nv);
      this.fanStart = new Uint32Array(n + 1);
      this.edgeStart = new Uint32Array(n + 1);
      let fans = 0, edges = 0;
      for (let f = 0; f < n; ++f) {
        fans += 3 * (scene.frag[4 * f + 1] - 2);
        edges += 2 * scene.frag[4 * f + 1];
      }
      this.fanIdx = new Uint32Array(fans);
      this.edgeIdx = new Uint32Array(edges);
      fans = 0, edges = 0;
      for (let f = 0; f < n; ++f) {
        const first = scene.frag[4 * f], count = scene.frag[4 * f + 1], color = scene.frag[4 * f + 3];
        for (let k = first; k < first + count; ++k) {
          colors[4 * k] = (color >>> 16) & 255;
          colors[4 * k + 1] = (color >>> 8) & 255;
          colors[4 * k + 2] = color & 255;
          colors[4 * k + 3] = 255;
          ids[k] = f + 1;
          normals[3 * k] = scene.frag_planes[4 * f];
          normals[3 * k + 1] = scene.frag_planes[4 * f + 1];
          normals[3 * k + 2] = scene.frag_planes[4 * f + 2];
        }
        this.fanStart[f] = fans;
        for (let v = 1; v + 1 < count; ++v) {
          this.fanIdx[fans++] = first;
          this.fanIdx[fans++] = first + v;
          this.fanIdx[fans++] = first + v + 1;
        }
        this.edgeStart[f] = edges;
        for (let v = 0; v < count; ++v) {
          this.edgeIdx[edges++] = first + v;
          this.edgeIdx[edges++] = first + (v + 1) % count;
        }
      }
      this.fanStart[n] = fans;
      this.edgeStart[n] = edges;
      this.relative = new Float32Array(3 * nv);
      this.lastEye = [NaN, NaN, NaN];
      this.clip = new Float32Array(16);
      this.frameIdx = new Uint32Array(Math.max(fans, edges, 3));

      this.program = this.link();
      this.clipLoc = gl.getUniformLocation(this.program, 'clip');
      this.styleLoc = gl.getUniformLocation(this.program, 'style');
      this.markerLoc = gl.getUniformLocation(this.program, 'marker');
      this.vao = gl.createVertexArray();
      gl.bindVertexArray(this.vao);
      this.posBuf = this.buffer(gl.ARRAY_BUFFER, this.relative, gl.DYNAMIC_DRAW);
      gl.enableVertexAttribArray(0);
      gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
      this.buffer(gl.ARRAY_BUFFER, colors, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(1);
      gl.vertexAttribPointer(1, 3, gl.UNSIGNED_BYTE, true, 4, 0);
      this.buffer(gl.ARRAY_BUFFER, ids, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(2);
      gl.vertexAttribIPointer(2, 1, gl.UNSIGNED_INT, 0, 0);
      this.buffer(gl.ARRAY_BUFFER, normals, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(3);
      gl.vertexAttribPointer(3, 3, gl.FLOAT, false, 0, 0);
      this.indexBuf = this.buffer(gl.ELEMENT_ARRAY_BUFFER, this.frameIdx, gl.STREAM_DRAW);
      gl.bindVertexArray(null);
      this.drawnMark = new Uint8Array(n);
      this.extra = new Uint32Array(n);
    }

    buffer(target, data, usage) {
      const gl = this.gl, b = gl.createBuffer();
      gl.bindBuffer(target, b);
      gl.bufferData(target, data, usage);
      return b;
    }

    link() {
      const gl = this.gl;
      const compile = (type, text) => {
        const s = gl.createShader(type);
        gl.shaderSource(s, text);
        gl.compileShader(s);
        if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
        return s;
      };
      const p = gl.createProgram();
      gl.attachShader(p, compile(gl.VERTEX_SHADER, kVertex));
      gl.attachShader(p, compile(gl.FRAGMENT_SHADER, kFragment));
      gl.linkProgram(p);
      if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(p));
      return p;
    }

    // Positions relative to the eye, subtracted in doubles and rounded to float as uploadEyeRelative
    // does: far from the origin (Doom maps) float positions would shake.
    updatePositions(eye) {
      const last = this.lastEye;
      if (last[0] === eye[0] && last[1] === eye[1] && last[2] === eye[2]) return;
      const v = this.scene.vertices, r = this.relative;
      for (let k = 0; k < r.length; k += 3) {
        r[k] = v[k] - eye[0];
        r[k + 1] = v[k + 1] - eye[1];
        r[k + 2] = v[k + 2] - eye[2];
      }
      const gl = this.gl;
      gl.bindBuffer(gl.ARRAY_BUFFER, this.posBuf);
      gl.bufferSubData(gl.ARRAY_BUFFER, 0, r);
      last[0] = eye[0], last[1] = eye[1], last[2] = eye[2];
    }

    // A list that names a fragment twice outgrows the one-of-each capacity: grow, never per frame.
    grow(need) {
      const gl = this.gl, idx = new Uint32Array(Math.ceil(need * 1.5));
      idx.set(this.frameIdx);
      this.frameIdx = idx;
      gl.bindVertexArray(this.vao);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indexBuf);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx.byteLength, gl.STREAM_DRAW);
    }

    append(list, n, at, wire) {
      const start = wire ? this.edgeStart : this.fanStart, idx = wire ? this.edgeIdx : this.fanIdx;
      let out = at;
      for (let i = 0; i < n; ++i) {
        const f = list[i];
        if (out + start[f + 1] - start[f] > this.frameIdx.length) this.grow(out + start[f + 1] - start[f]);
        for (let k = start[f]; k < start[f + 1]; ++k) this.frameIdx[out++] = idx[k];
      }
      return out;
    }

    // Draws order.ids[0, order.n); with `rejected`, then the fragments left out that face the eye
    // in the marker colour (the window's "show rejected"). Returns the rejected count drawn.
    // With `zbuffer`, the depth test on (the reference frame of `?bench`: every fragment, any order).
    draw(cam, order, style, zbuffer = false) {
      const gl = this.gl, sc = this.scene;
      this.updatePositions(cam.eye);
      gl.viewport(0, 0, cam.width, cam.height);
      if (style.ids) gl.clearColor(0, 0, 0, 1);
      else gl.clearColor(0.12, 0.13, 0.16, 1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      if (zbuffer) {
        gl.enable(gl.DEPTH_TEST);
        gl.depthFunc(gl.LESS);
      } else {
        gl.disable(gl.DEPTH_TEST);
      }
      gl.disable(gl.CULL_FACE);
      gl.disable(gl.BLEND);
      gl.disable(gl.DITHER);  // ids must reach the buffer bit-exact
      gl.useProgram(this.program);
      gl.uniformMatrix4fv(this.clipLoc, false, W.clipMatrix(cam, this.clip));
      gl.uniform1i(this.styleLoc, style.ids ? 1 : 0);
      gl.uniform1i(this.markerLoc, 0);
      gl.bindVertexArray(this.vao);
      const first = this.append(order.ids, order.n, 0, style.wire);
      let extra = 0;
      if (style.rejected) {
        this.drawnMark.fill(0);
        for (let i = 0; i < order.n; ++i) this.drawnMark[order.ids[i]] = 1;
        const p = sc.frag_planes, e = cam.eye;
        for (let f = 0; f < sc.meta.fragments; ++f)
          if (!this.drawnMark[f] && W.planeSign(p[4 * f], p[4 * f + 1], p[4 * f + 2], p[4 * f + 3], e[0], e[1], e[2]) > 0)
            this.extra[extra++] = f;
      }
      const total = this.append(this.extra, extra, first, style.wire);
      if (total === 0) return 0;
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indexBuf);
      gl.bufferSubData(gl.ELEMENT_ARRAY_BUFFER, 0, this.frameIdx, 0, total);
      const mode = style.wire ? gl.LINES : gl.TRIANGLES;
      if (first > 0) gl.drawElements(mode, first, gl.UNSIGNED_INT, 0);
      if (total > first) {
        gl.uniform1i(this.markerLoc, 1);
        gl.drawElements(mode, total - first, gl.UNSIGNED_INT, 4 * first);
      }
      gl.bindVertexArray(null);
      return extra;
    }
  }

  // ---- the page -----------------------------------------------------------------------------
  function parseSize(text) {
    const m = /^(\d+)x(\d+)$/.exec(text || '640x480');
    if (!m || +m[1] < 1 || +m[2] < 1 || +m[1] > 8192 || +m[2] > 8192) throw new Error('size=' + text + ': expected WxH');
    return [+m[1], +m[2]];
  }

  // One camera and one frame record per page, refilled each frame: a frame allocates nothing.
  function setCamera(cam, eye, yaw, pitch, width, height) {
    cam.eye[0] = eye[0], cam.eye[1] = eye[1], cam.eye[2] = eye[2];
    cam.yaw = yaw, cam.pitch = pitch, cam.width = width, cam.height = height;
    return cam;
  }

  function overlayText(scene, stats) {
    const m = scene.meta, deg = 180 / Math.PI;
    const loaded = scene.cells.filter((c) => c.tree).length;
    const where = stats.order.used === 'hfd' ? 'HFD tree of level ' + stats.order.level
                : stats.order.waiting ? 'BSP order (view cell ' + stats.order.waiting.index + ' still loading)'
                                      : 'BSP order (no tree here: stairs or off the height plane)';
    return [
      'walkvis · ' + m.source,
      'drawn ' + stats.order.n + ' of ' + m.fragments + ' polygons · ' + stats.order.tests + ' tests · ' + where,
      'view cells loaded ' + loaded + ' of ' + scene.cells.length,
      'walk level ' + stats.walk_level + ' · eye (' + stats.eye.map((x) => x.toFixed(2)).join(', ') + ') yaw ' +
          (stats.yaw * deg).toFixed(1) + '° pitch ' + (stats.pitch * deg).toFixed(1) + '°',
      'frame ' + stats.frame_ms.toFixed(2) + ' ms (order ' + stats.order_ms.toFixed(2) + ') · ' +
          (stats.rejected_shown ? stats.rejected_shown + ' rejected shown · ' : '') + (stats.fps ? stats.fps.toFixed(0) + ' fps' : ''),
      '[F] wireframe ' + (stats.style.wire ? 'on' : 'off') + '  [R] rejected ' + (stats.style.rejected ? 'on' : 'off') +
          '  [I] ids ' + (stats.style.ids ? 'on' : 'off') + '  [H] overlay',
      'WASD walk · Shift run · click, then mouse to look · Esc releases',
    ].join('\n');
  }

  function start(scene, cells) {
    const gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: true, preserveDrawingBuffer: true });
    if (!gl) throw new Error('this browser has no WebGL2');
    const renderer = new Renderer(gl, scene);
    const walker = new W.Walker(scene);
    const order = W.makeOrder(scene);
    const style = { ids: params.get('ids') === '1', wire: params.get('wire') === '1', rejected: params.get('rejected') === '1' };
    // &cells=none: no view cell is fetched, every frame takes the BSP order (what a page shows
    // until its cell arrives); otherwise a view waits for the cells of its eyes.
    const fetchCells = params.get('cells') !== 'none';
    const cellsFor = (eyes) => {
      const need = new Set();
      for (const e of eyes) {
        const c = W.cellAt(scene, e);
        if (c && !c.tree) need.add(c);
      }
      return fetchCells ? Promise.all([...need].map(cells.load)) : Promise.resolve();
    };
    const tour = scene.meta.tour;

    const view = (() => {
      if (params.has('frame')) {
        const k = Number(params.get('frame'));
        if (!(Number.isInteger(k) && k >= 0 && k < tour.length))
          throw new Error('frame=' + params.get('frame') + ': the tour has keys 0 to ' + (tour.length - 1));
        const key = tour[k];
        return { eye: [key[1], key[2], key[3]], yaw: key[4], pitch: key[5] };
      }
      if (params.has('eye')) {
        const e = params.get('eye').split(',').map(Number);
        const yaw = Number(params.get('yaw') || 0), pitch = Number(params.get('pitch') || 0);
        if (e.length !== 3 || !e.every(isFinite) || !isFinite(yaw) || !(Math.abs(pitch) < Math.PI / 2))
          throw new Error('eye=x,y,z&yaw=Y&pitch=P expected (|pitch| < pi/2)');
        return { eye: e, yaw, pitch };
      }
      return null;
    })();

    const c = scene.meta.camera;
    const cam = { eye: [0, 0, 0], yaw: 0, pitch: 0, fov_y: c.fov_y, near: c.near, far: c.far, width: 1, height: 1 };
    const drawn = { order, order_ms: 0, t0: 0, t1: 0, t2: 0, rejected: 0 };
    // Fixed orders for ?bench's other runs: every fragment (the z-buffer) and none (the floor).
    const all = W.makeOrder(scene), none = W.makeOrder(scene);
    for (let f = 0; f < scene.meta.fragments; ++f) all.ids[f] = f;
    all.n = scene.meta.fragments;
    // t0 → t1 the order, t1 → t2 the GL calls (the rasteriser may still be working at t2). `run`:
    // 'hfd' (the frame's order, what the walkthrough draws), 'bsp' (the BSP's back-to-front order
    // everywhere), 'zbuffer' (every fragment, depth test on) or 'floor' (nothing drawn).
    const orderFor = (eye, run) => {
      if (run === 'hfd') W.frameOrder(scene, eye, order);
      else if (run === 'bsp') order.n = 0, W.bspOrder(scene, eye, order);
      else return run === 'zbuffer' ? all : none;
      return order;
    };
    const drawView = (eye, yaw, pitch, width, height, run = 'hfd') => {
      setCamera(cam, eye, yaw, pitch, width, height);
      drawn.t0 = performance.now();
      drawn.order = orderFor(cam.eye, run);
      drawn.t1 = performance.now();
      drawn.rejected = renderer.draw(cam, drawn.order, style, run === 'zbuffer');
      drawn.t2 = performance.now();
      drawn.order_ms = drawn.t1 - drawn.t0;
      return drawn;
    };

    if (params.has('bench')) {
      const keys = Math.min(Number(params.get('bench')) || 20, tour.length), reps = Math.max(Number(params.get('reps')) || 5, 1);
      cellsFor(tour.slice(0, keys).map((key) => [key[1], key[2], key[3]])).then(() => {
        document.body.dataset.cellsMs = performance.now().toFixed(1);  // the keys' cells in hand
        const [w, h] = parseSize(params.get('size'));
        canvas.width = w, canvas.height = h;
        canvas.style.width = w + 'px', canvas.style.height = h + 'px';
        overlayEl.style.display = 'none';
        // Each run draws the keys in turn, every frame finished by a one-pixel read-back (which waits
        // for the rasteriser); runs rotate their order each repetition, so that drift in the machine's
        // speed falls on all alike. The floor is what a frame costs with nothing drawn.
        const runs = ['floor', 'zbuffer', 'bsp', 'hfd'];
        const pixel = new Uint8Array(4);
        const rec = {};
        for (const run of runs) rec[run] = { total: [], order: [], submit: [], wait: [], drawn: 0 };
        for (let r = 0; r < reps; ++r) {
          for (let j = 0; j < runs.length; ++j) {
            const run = runs[(j + r) % runs.length], m = rec[run];
            for (let k = 0; k < keys; ++k) {
              const key = tour[k];
              const d = drawView([key[1], key[2], key[3]], key[4], key[5], w, h, run);
              gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
              const t3 = performance.now();
              m.total.push(t3 - d.t0), m.order.push(d.t1 - d.t0), m.submit.push(d.t2 - d.t1), m.wait.push(t3 - d.t2);
              if (r === 0) m.drawn += d.order.n / keys;
            }
          }
        }
        const median = (a) => { const b = a.slice().sort((x, y) => x - y); return b[Math.floor(b.length / 2)]; };
        const modes = {};
        for (const run of runs) {
          const m = rec[run];
          modes[run] = { frame_ms_median: median(m.total), order_ms_median: median(m.order), submit_ms_median: median(m.submit),
                         wait_ms_median: median(m.wait), drawn_mean: m.drawn };
        }
        // An order alone is below the clock's step (0.1 ms in a page without cross-origin isolation):
        // each is timed again over many calls, the keys in turn, for the mean in microseconds.
        for (const run of ['bsp', 'hfd']) {
          let calls = 0;
          const t = performance.now();
          do {
            for (let k = 0; k < keys; ++k, ++calls) {
              const key = tour[k];
              cam.eye[0] = key[1], cam.eye[1] = key[2], cam.eye[2] = key[3];
              orderFor(cam.eye, run);
            }
          } while (performance.now() - t < 200);
          modes[run].order_us_mean = 1000 * (performance.now() - t) / calls;
        }
        const hfd = modes.hfd;
        document.body.dataset.bench = JSON.stringify({
          keys, reps, width: w, height: h, fragments: scene.meta.fragments,
          frame_ms_median: hfd.frame_ms_median, drawn_mean: hfd.drawn_mean, floor_ms_median: modes.floor.frame_ms_median,
          hfd_speedup: modes.zbuffer.frame_ms_median / hfd.frame_ms_median, modes });
        document.body.dataset.drawn = '1';
        document.title = 'walkvis: bench done';
      }).catch(fail);
      return;
    }

    if (view) {
      cellsFor([view.eye]).then(() => {
        document.body.dataset.cellsMs = performance.now().toFixed(1);  // the view's cell in hand
        const [w, h] = parseSize(params.get('size'));
        canvas.width = w, canvas.height = h;
        canvas.style.width = w + 'px', canvas.style.height = h + 'px';
        const d = drawView(view.eye, view.yaw, view.pitch, w, h);
        gl.finish();
        if (params.get('overlay') === '1') {
          overlayEl.textContent = overlayText(scene, { order: d.order, walk_level: walker.place(view.eye).level, eye: view.eye,
            yaw: view.yaw, pitch: view.pitch, frame_ms: performance.now() - d.t0, order_ms: d.order_ms, style, rejected_shown: d.rejected });
        } else {
          overlayEl.style.display = 'none';
        }
        document.body.dataset.drawnMs = performance.now().toFixed(1);
        document.body.dataset.drawn = '1';
        document.body.dataset.polygons = String(d.order.n);
        document.body.dataset.tests = String(d.order.tests);
        document.body.dataset.used = d.order.used;
        document.title = 'walkvis: drawn';
      }).catch(fail);
      return;
    }

    // The walkthrough.
    const s = scene.meta.start, walk = scene.meta.walk;
    let state = walker.place(s.eye);
    let yaw = s.yaw, pitch = 0;
    const keys = new Set();
    let showOverlay = params.get('overlay') !== '0';
    window.addEventListener('keydown', (e) => {
      keys.add(e.code);
      if (e.code === 'KeyF') style.wire = !style.wire;
      if (e.code === 'KeyR') style.rejected = !style.rejected;
      if (e.code === 'KeyI') style.ids = !style.ids;
      if (e.code === 'KeyH') showOverlay = !showOverlay;
    });
    window.addEventListener('keyup', (e) => keys.delete(e.code));
    window.addEventListener('blur', () => keys.clear());
    canvas.addEventListener('click', () => { if (canvas.requestPointerLock) canvas.requestPointerLock(); });
    document.addEventListener('mousemove', (e) => {
      if (document.pointerLockElement !== canvas) return;
      yaw -= e.movementX * walk.mouse_radians_per_pixel;
      pitch = Math.min(Math.max(pitch - e.movementY * walk.mouse_radians_per_pixel, -walk.max_pitch), walk.max_pitch);
    });
    const resize = () => {
      const dpr = window.devicePixelRatio || 1;
      canvas.width = Math.max(1, Math.floor(window.innerWidth * dpr));
      canvas.height = Math.max(1, Math.floor(window.innerHeight * dpr));
      canvas.style.width = window.innerWidth + 'px', canvas.style.height = window.innerHeight + 'px';
    };
    window.addEventListener('resize', resize);
    resize();
    let last = null, fps = 0, frameMs = 0, shown = 0;
    const frame = (now) => {
      const dt = last === null ? 0 : Math.min((now - last) / 1000, 0.1);
      last = now;
      let wx = 0, wz = 0;
      const fx = -Math.sin(yaw), fz = -Math.cos(yaw), rx = Math.cos(yaw), rz = -Math.sin(yaw);
      if (keys.has('KeyW')) wx += fx, wz += fz;
      if (keys.has('KeyS')) wx -= fx, wz -= fz;
      if (keys.has('KeyD')) wx += rx, wz += rz;
      if (keys.has('KeyA')) wx -= rx, wz -= rz;
      const len = Math.hypot(wx, wz);
      if (len > 0 && dt > 0) {
        const run = keys.has('ShiftLeft') || keys.has('ShiftRight');
        const step = walk.speed * (run ? walk.run_factor : 1) * dt / len;
        walker.move(state, wx * step, wz * step, state);
      }
      const d = drawView(state.eye, yaw, pitch, canvas.width, canvas.height);
      if (d.order.waiting && fetchCells) cells.load(d.order.waiting);
      const ms = performance.now() - d.t0;
      frameMs = frameMs === 0 ? ms : 0.9 * frameMs + 0.1 * ms;
      if (dt > 0) fps = fps === 0 ? 1 / dt : 0.95 * fps + 0.05 / dt;
      overlayEl.style.display = showOverlay ? 'block' : 'none';
      if (showOverlay && ++shown % 8 === 1) {
        overlayEl.textContent = overlayText(scene, { order: d.order, walk_level: state.level, eye: state.eye, yaw, pitch,
          frame_ms: frameMs, order_ms: d.order_ms, style, fps, rejected_shown: d.rejected });
      }
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
    // The cell the walk starts in first, then the rest in the background (&prefetch=0: only the
    // cells the walk enters, each when it gets there).
    if (fetchCells) {
      const first = W.cellAt(scene, state.eye);
      const then = () => { if (params.get('prefetch') !== '0') cells.prefetch(() => state.eye); };
      if (first && !first.tree) cells.load(first).then(then, () => {});
      else then();
    }
  }

  const fail = (e) => showError(e instanceof W.ExportError ? e.message : 'walkvis: ' + e.message);
  let parseStart = 0;
  fileBytes('walkvis.bin', 'walkvis-data.js', (take) => { window.walkvisData = take; })
    .then((buffer) => {
      parseStart = performance.now();
      return W.parseExport(buffer, 'walkvis.bin');
    })
    .then((scene) => {
      // Load time: from the navigation's start to walkvis.bin read and checked (bytes fetched or
      // decoded from base64, sections checksummed and inflated, arrays mapped); its parts: this
      // script started, the bytes in hand, the parse. View cells come after (cellLoader).
      document.body.dataset.loadMs = performance.now().toFixed(1);
      document.body.dataset.scriptMs = scriptMs.toFixed(1);
      document.body.dataset.bytesMs = parseStart.toFixed(1);
      document.body.dataset.parseMs = (performance.now() - parseStart).toFixed(1);
      start(scene, cellLoader(scene, fail));
    })
    .catch(fail);
})();

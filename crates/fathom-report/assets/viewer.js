// fathom scene page viewer: decodes the page's data (a JSON header and base64 typed
// arrays in NED metres), draws the world, paths, scans and satellite lines of sight
// with three.js (window.FATHOM_THREE), and drives them with a time slider.
// window.FATHOM_SCENE exposes the decoded data and the controls to tests.
(function () {
  'use strict';
  var T = window.FATHOM_THREE;
  var header = JSON.parse(document.getElementById('fathom-header').textContent);
  var raw = atob(document.getElementById('fathom-data').textContent.trim());
  var bytes = new Uint8Array(raw.length);
  for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  var buf = bytes.buffer;

  function arr(r) {
    if (r.t === 'f32') return new Float32Array(buf, r.o, r.n);
    if (r.t === 'u32') return new Uint32Array(buf, r.o, r.n);
    return new Uint8Array(buf, r.o, r.n);
  }
  // NED (north, east, down) -> three.js (x east, y up, z south): right-handed.
  function v3(a, k) { return new T.Vector3(a[3 * k + 1], -a[3 * k + 2], -a[3 * k]); }
  function toThree(a) {
    var out = new Float32Array(a.length);
    for (var k = 0; k < a.length; k += 3) { out[k] = a[k + 1]; out[k + 1] = -a[k + 2]; out[k + 2] = -a[k]; }
    return out;
  }

  function decode(s) {
    var d = {
      name: s.name, styles: s.styles,
      mesh: { v: arr(s.mesh.v), i: arr(s.mesh.i), m: arr(s.mesh.m) },
      times: arr(s.times), truth: arr(s.truth),
      methods: s.methods.map(function (m) {
        return { name: m.name, modes: m.modes, pos: arr(m.pos), mode: arr(m.mode), err: arr(m.err) };
      }),
      scans: { t: arr(s.scans.t), o: arr(s.scans.o), n: arr(s.scans.n), h: arr(s.scans.h) },
      sky: { t: arr(s.sky.t), n: arr(s.sky.n), d: arr(s.sky.d), v: arr(s.sky.v) }
    };
    d.scans.start = prefix(d.scans.n);
    d.sky.start = prefix(d.sky.n);
    return d;
  }
  function prefix(n) {
    var s = new Uint32Array(n.length + 1);
    for (var k = 0; k < n.length; k++) s[k + 1] = s[k] + n[k];
    return s;
  }
  // The last index whose time is <= t (0 if none).
  function before(times, t) {
    var lo = 0, hi = times.length - 1;
    if (hi < 0) return -1;
    if (times[0] > t) return 0;
    while (lo < hi) { var mid = (lo + hi + 1) >> 1; if (times[mid] <= t) lo = mid; else hi = mid - 1; }
    return lo;
  }

  var scenes = header.scenes.map(decode);
  var PALETTE = [0x4e79a7, 0xf28e2b, 0xe15759, 0x76b7b2, 0x59a14f, 0xedc948, 0xb07aa1, 0xff9da7, 0x9c755f];

  // ---- DOM ----
  var app = document.getElementById('app');
  var panel = document.createElement('div');
  panel.id = 'panel';
  panel.innerHTML =
    '<h1></h1><div class="note"></div>' +
    '<div class="row"><label>scene <select id="sceneSel"></select></label>' +
    '<label>method <select id="methodSel"></select></label></div>' +
    '<div class="row"><button id="play">play</button> ' +
    '<label><input type="checkbox" id="follow"> follow the vehicle</label>' +
    '<label>speed <select id="speed"><option>1</option><option selected>5</option><option>20</option></select>x</label></div>' +
    '<input type="range" id="slider" min="0" max="0" value="0" step="1">' +
    '<div id="status"></div><div id="legend"></div>';
  document.body.appendChild(panel);
  panel.querySelector('h1').textContent = header.title;
  panel.querySelector('.note').textContent = header.note;
  var sceneSel = document.getElementById('sceneSel');
  var methodSel = document.getElementById('methodSel');
  var slider = document.getElementById('slider');
  var playBtn = document.getElementById('play');
  var followBox = document.getElementById('follow');
  var speedSel = document.getElementById('speed');
  var statusEl = document.getElementById('status');
  var legendEl = document.getElementById('legend');
  scenes.forEach(function (s, k) { var o = document.createElement('option'); o.value = k; o.textContent = s.name; sceneSel.appendChild(o); });

  // ---- three.js ----
  var renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.setClearColor(0x1d2126);
  app.appendChild(renderer.domElement);
  var scene3 = new T.Scene();
  var camera = new T.PerspectiveCamera(50, window.innerWidth / window.innerHeight, 0.1, 20000);
  var controls = new T.OrbitControls(camera, renderer.domElement);
  controls.addEventListener('change', function () { dirty = true; });
  scene3.add(new T.AmbientLight(0xffffff, 0.9));
  var sun = new T.DirectionalLight(0xffffff, 1.6);
  sun.position.set(0.4, 1.0, 0.6);
  scene3.add(sun);

  var world = null, current = null, epoch = 0, dirty = true, playing = false, lastTick = 0, playTime = 0;
  var vehicle = new T.Mesh(new T.SphereGeometry(1, 16, 12), new T.MeshLambertMaterial({ color: 0xffffff }));
  var estMarker = new T.Mesh(new T.SphereGeometry(0.7, 12, 8), new T.MeshBasicMaterial({ color: 0xffffff }));
  var beams = new T.LineSegments(new T.BufferGeometry(), new T.LineBasicMaterial({ color: 0xffe066, transparent: true, opacity: 0.55 }));
  var hits = new T.Points(new T.BufferGeometry(), new T.PointsMaterial({ color: 0xffcc00, size: 0.6 }));
  var sats = new T.LineSegments(new T.BufferGeometry(), new T.LineBasicMaterial({ vertexColors: true }));
  [vehicle, estMarker, beams, hits, sats].forEach(function (o) { o.frustumCulled = false; });

  function buildScene(k) {
    if (world) scene3.remove(world);
    current = scenes[k];
    var s = current;
    world = new T.Group();
    // The mesh, one geometry per material (glass translucent).
    var pos = new T.BufferAttribute(toThree(s.mesh.v), 3);
    s.styles.forEach(function (st, mi) {
      var idx = [];
      for (var t = 0; t < s.mesh.m.length; t++) if (s.mesh.m[t] === mi) idx.push(s.mesh.i[3 * t], s.mesh.i[3 * t + 1], s.mesh.i[3 * t + 2]);
      if (!idx.length) return;
      var g = new T.BufferGeometry();
      g.setAttribute('position', pos);
      g.setIndex(idx);
      g.computeVertexNormals();
      var glass = st.opacity < 1;
      var mat = new T.MeshLambertMaterial({ color: st.color, transparent: glass, opacity: st.opacity, side: T.DoubleSide, depthWrite: !glass });
      var mesh = new T.Mesh(g, mat);
      mesh.name = 'world:' + st.name;
      if (glass) mesh.renderOrder = 2;
      world.add(mesh);
    });
    // Bounds of the world and the path.
    var box = { min: [Infinity, Infinity, Infinity], max: [-Infinity, -Infinity, -Infinity] };
    function grow(a) { var p = toThree(a); for (var j = 0; j < p.length; j++) { var c = j % 3; if (p[j] < box.min[c]) box.min[c] = p[j]; if (p[j] > box.max[c]) box.max[c] = p[j]; } }
    grow(s.mesh.v);
    var worldBox = { min: box.min.slice(), max: box.max.slice() };
    // The camera frames the true path (a wide ground or a drifting estimate would
    // make the flight a speck), the grid covers the world.
    box = { min: [Infinity, Infinity, Infinity], max: [-Infinity, -Infinity, -Infinity] };
    grow(s.truth);
    var cx = (box.min[0] + box.max[0]) / 2, cz = (box.min[2] + box.max[2]) / 2;
    var span = Math.max(box.max[0] - box.min[0], box.max[2] - box.min[2], 40);
    var gx = (worldBox.min[0] + worldBox.max[0]) / 2, gz = (worldBox.min[2] + worldBox.max[2]) / 2;
    var gspan = Math.max(worldBox.max[0] - worldBox.min[0], worldBox.max[2] - worldBox.min[2], span);
    var grid = new T.GridHelper(Math.ceil(gspan * 1.4 / 10) * 10, Math.ceil(gspan * 1.4 / 10), 0x555a60, 0x3a3f45);
    grid.position.set(gx, Math.min(0, worldBox.min[1]) - 0.05, gz);
    world.add(grid);
    // Markers sized to the scene: visible from the initial view, small near it.
    var r = Math.max(0.4, span / 150);
    vehicle.scale.setScalar(r);
    estMarker.scale.setScalar(r);
    hits.material.size = r * 0.6;
    // The true path.
    var tg = new T.BufferGeometry();
    tg.setAttribute('position', new T.BufferAttribute(toThree(s.truth), 3));
    world.add(new T.Line(tg, new T.LineBasicMaterial({ color: 0xffffff })));
    // Each method's path; epochs in a mode after the first are marked by points.
    s.methods.forEach(function (m, mi) {
      var col = PALETTE[mi % PALETTE.length];
      var g = new T.BufferGeometry();
      g.setAttribute('position', new T.BufferAttribute(toThree(m.pos), 3));
      var line = new T.Line(g, new T.LineBasicMaterial({ color: col }));
      line.name = 'path:' + m.name;
      world.add(line);
      var marks = [];
      for (var e = 0; e < m.mode.length; e++) if (m.mode[e] > 0) { var p = v3(m.pos, e); marks.push(p.x, p.y, p.z); }
      if (marks.length) {
        var mg = new T.BufferGeometry();
        mg.setAttribute('position', new T.BufferAttribute(new Float32Array(marks), 3));
        world.add(new T.Points(mg, new T.PointsMaterial({ color: col, size: 1.2 })));
      }
    });
    [vehicle, estMarker, beams, hits, sats].forEach(function (o) { world.add(o); });
    scene3.add(world);
    methodSel.innerHTML = '';
    legendEl.innerHTML = '<div><span class="sw" style="background:#fff"></span>truth</div>';
    s.methods.forEach(function (m, mi) {
      var o = document.createElement('option'); o.value = mi; o.textContent = m.name; methodSel.appendChild(o);
      var col = '#' + PALETTE[mi % PALETTE.length].toString(16).padStart(6, '0');
      var dv = document.createElement('div');
      dv.innerHTML = '<span class="sw"></span>';
      dv.firstChild.style.background = col;
      dv.appendChild(document.createTextNode(m.name + (m.modes.length > 1 ? ' (dots: ' + m.modes.slice(1).join(', ') + ')' : '')));
      legendEl.appendChild(dv);
    });
    var pick = s.methods.findIndex(function (m) { return m.modes.length > 1 && m.mode.some(function (x) { return x > 0; }); });
    methodSel.value = pick >= 0 ? pick : 0;
    var ex = document.createElement('div');
    ex.textContent = 'beams: yellow; satellites: green in view, red blocked';
    legendEl.appendChild(ex);
    slider.max = Math.max(0, s.times.length - 1);
    // A three-quarter view from above the path, high enough to clear the world's top.
    var ty = (box.min[1] + box.max[1]) / 2;
    camera.position.set(cx + span * 0.55, Math.max(ty + span * 0.8, worldBox.max[1] + span * 0.3), cz + span * 0.85);
    controls.target.set(cx, ty, cz);
    controls.update();
    setEpoch(0);
  }

  function setEpoch(k) {
    var s = current;
    epoch = Math.max(0, Math.min(k, s.times.length - 1));
    slider.value = epoch;
    var t = s.times[epoch];
    var p = v3(s.truth, epoch);
    vehicle.position.copy(p);
    var mi = Number(methodSel.value) || 0;
    var m = s.methods[mi];
    var text = 't = ' + t.toFixed(1) + ' s';
    if (m) {
      estMarker.position.copy(v3(m.pos, epoch));
      estMarker.material.color.setHex(PALETTE[mi % PALETTE.length]);
      text += '   ' + m.name + ': error ' + m.err[epoch].toFixed(2) + ' m, mode ' + m.modes[m.mode[epoch]];
    }
    // The latest scan at or before t.
    var sc = s.scans, bp = [], hp = [];
    var j = before(sc.t, t);
    if (j >= 0 && sc.t[j] <= t + 1e-3) {
      var o = v3(sc.o, j);
      for (var h = sc.start[j]; h < sc.start[j + 1]; h++) {
        var q = v3(sc.h, h);
        bp.push(o.x, o.y, o.z, q.x, q.y, q.z); hp.push(q.x, q.y, q.z);
      }
    }
    beams.geometry.setAttribute('position', new T.BufferAttribute(new Float32Array(bp), 3));
    hits.geometry.setAttribute('position', new T.BufferAttribute(new Float32Array(hp), 3));
    // The satellites of the latest GNSS epoch, drawn from the vehicle.
    var sk = s.sky, sp = [], scol = [], inView = 0, total = 0;
    var g = before(sk.t, t);
    if (g >= 0 && sk.t[g] <= t + 1e-3) {
      for (var n = sk.start[g]; n < sk.start[g + 1]; n++) {
        var d = v3(sk.d, n), len = 60, vis = sk.v[n] === 1;
        sp.push(p.x, p.y, p.z, p.x + d.x * len, p.y + d.y * len, p.z + d.z * len);
        var c = vis ? [0.2, 0.85, 0.3] : [0.9, 0.2, 0.2];
        scol.push(c[0], c[1], c[2], c[0], c[1], c[2]);
        total++; if (vis) inView++;
      }
      text += '\nsatellites in view ' + inView + ' / ' + total;
    }
    sats.geometry.setAttribute('position', new T.BufferAttribute(new Float32Array(sp), 3));
    sats.geometry.setAttribute('color', new T.BufferAttribute(new Float32Array(scol), 3));
    statusEl.textContent = text;
    if (followBox.checked) {
      var off = camera.position.clone().sub(controls.target);
      controls.target.copy(p);
      camera.position.copy(p).add(off);
      controls.update();
    }
    dirty = true;
  }

  var frames = 0;
  function loop(now) {
    if (playing) {
      var s = current;
      var dt = lastTick ? (now - lastTick) / 1000 : 0;
      playTime += dt * Number(speedSel.value);
      var k = before(s.times, playTime);
      if (k !== epoch) setEpoch(k);
      if (epoch >= s.times.length - 1) { playing = false; playBtn.textContent = 'play'; }
    }
    lastTick = now;
    if (dirty) { renderer.render(scene3, camera); frames++; dirty = false; }
    requestAnimationFrame(loop);
  }

  sceneSel.addEventListener('change', function () { buildScene(Number(sceneSel.value)); });
  methodSel.addEventListener('change', function () { setEpoch(epoch); });
  slider.addEventListener('input', function () { setEpoch(Number(slider.value)); playTime = current.times[epoch]; });
  followBox.addEventListener('change', function () { setEpoch(epoch); });
  playBtn.addEventListener('click', function () {
    playing = !playing;
    if (playing && epoch >= current.times.length - 1) setEpoch(0);
    playTime = current.times[epoch];
    playBtn.textContent = playing ? 'pause' : 'play';
  });
  window.addEventListener('resize', function () {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    dirty = true;
  });

  var start = 0, want = /[#&]scene=([^&]+)/.exec(location.hash);
  if (want) { var w = scenes.findIndex(function (s) { return s.name === decodeURIComponent(want[1]); }); if (w >= 0) start = w; }
  sceneSel.value = start;
  buildScene(start);
  requestAnimationFrame(loop);

  window.FATHOM_SCENE = {
    header: header,
    scenes: scenes,
    frames: function () { return frames; },
    epoch: function () { return epoch; },
    setScene: function (k) { sceneSel.value = k; buildScene(k); },
    setEpoch: setEpoch,
    statusText: function () { return statusEl.textContent; }
  };
})();

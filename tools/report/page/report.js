// report.html's script (tools/report/report_html.h): builds the page from the run's data (the
// JSON in <script id="dala-data">, tools/report/report_data.h) with three.js r147 (global THREE,
// THREE.OrbitControls). Renders on demand (no animation loop unless playing). Its state goes into
// document.title: "dala report: ready" once drawn, "dala report: error: ..." otherwise.
(function () {
  'use strict';

  // Colours the headless-browser test looks for (tests/tools/report_browser_test.cc).
  const COLOUR_PATH = 0xff3030;    // The estimated trajectory.
  const COLOUR_MARKER = 0xff00ff;  // The camera at the slider's time.
  const COLOUR_GT = 0xb8b8b8;
  const COLOUR_KEYFRAME = 0x3c96ff;
  const COLOUR_LOOP_CLOSED = 0x30ff30;
  const COLOUR_LOOP_DETECTED = 0xc8c800;
  const COLOUR_LOST = 0xffa000;
  const COLOUR_RELOCALISED = 0x00e0ff;

  function setStatus(s) { document.title = 'dala report: ' + s; }
  window.addEventListener('error', function (e) { setStatus('error: ' + e.message); });

  const data = JSON.parse(document.getElementById('dala-data').textContent);
  const app = document.getElementById('app');

  function el(tag, attrs, parent, text) {
    const e = document.createElement(tag);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    if (parent) parent.appendChild(e);
    return e;
  }
  function hex(c) { return '#' + c.toString(16).padStart(6, '0'); }

  // ---- Layout ----
  const viewCol = el('div', {id: 'view-col'}, app);
  const toolbar = el('div', {id: 'toolbar'}, viewCol);
  el('span', {class: 'title'}, toolbar, data.title || 'dala run');
  const buttons = {};
  for (const name of ['Top', 'Side', 'Oblique']) buttons[name] = el('button', {}, toolbar, name);
  const view = el('div', {id: 'view'}, viewCol);
  const legend = el('div', {id: 'legend'}, view);
  const timebar = el('div', {id: 'timebar'}, viewCol);
  const play = el('button', {}, timebar, 'Play');
  const slider = el('input', {type: 'range', min: '0', max: '1000', value: '0'}, timebar);
  const timeLabel = el('span', {class: 'label'}, timebar, '');
  const side = el('div', {id: 'side'}, app);

  function addLegend(colour, text) {
    const s = el('span', {class: 'swatch'}, legend);
    s.style.background = hex(colour);
    legend.appendChild(document.createTextNode(text));
  }

  // ---- Data ----
  function vectors(flat) {
    const out = [];
    if (!flat) return out;
    for (let i = 0; i + 2 < flat.length; i += 3) {
      out.push(new THREE.Vector3(flat[i], flat[i + 1], flat[i + 2]));
    }
    return out;
  }
  function quaternions(flat) {
    const out = [];
    if (!flat) return out;
    for (let i = 0; i + 3 < flat.length; i += 4) {
      out.push(new THREE.Quaternion(flat[i], flat[i + 1], flat[i + 2], flat[i + 3]));
    }
    return out;
  }
  const path = vectors(data.path.xyz);
  const pathQ = quaternions(data.path.q);
  const pathT = data.path.t || [];
  const gt = data.ground_truth ? vectors(data.ground_truth.xyz) : [];
  const keyframes = vectors(data.keyframes.xyz);
  const keyframesQ = quaternions(data.keyframes.q);
  const up = new THREE.Vector3().fromArray(data.up).normalize();
  const charts = data.charts;
  const tEnd = Math.max(pathT.length ? pathT[pathT.length - 1] : 0,
                        charts.t.length ? charts.t[charts.t.length - 1] : 0);

  // The scene's extent: the paths, the keyframes and the bulk of the map (each axis between its
  // 10th and 90th percentile: a map may hold far outliers).
  const box = new THREE.Box3();
  for (const p of path) box.expandByPoint(p);
  for (const p of gt) box.expandByPoint(p);
  for (const p of keyframes) box.expandByPoint(p);
  const pointsFlat = data.points.xyz;
  if (pointsFlat.length >= 30) {
    const n = pointsFlat.length / 3;
    const step = Math.max(1, Math.floor(n / 20000));
    const lo = [], hi = [];
    for (let c = 0; c < 3; ++c) {
      const values = [];
      for (let i = 0; i < n; i += step) values.push(pointsFlat[3 * i + c]);
      values.sort(function (a, b) { return a - b; });
      lo.push(values[Math.floor(0.1 * (values.length - 1))]);
      hi.push(values[Math.floor(0.9 * (values.length - 1))]);
    }
    box.expandByPoint(new THREE.Vector3().fromArray(lo));
    box.expandByPoint(new THREE.Vector3().fromArray(hi));
  } else {
    for (let i = 0; i + 2 < pointsFlat.length; i += 3) {
      box.expandByPoint(new THREE.Vector3(pointsFlat[i], pointsFlat[i + 1], pointsFlat[i + 2]));
    }
  }
  if (box.isEmpty()) box.expandByPoint(new THREE.Vector3(0, 0, 0));
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1.0);

  // Two horizontal directions (perpendicular to up).
  const axes = [new THREE.Vector3(1, 0, 0), new THREE.Vector3(0, 1, 0), new THREE.Vector3(0, 0, 1)];
  axes.sort(function (a, b) { return Math.abs(a.dot(up)) - Math.abs(b.dot(up)); });
  const h1 = axes[0].clone().addScaledVector(up, -axes[0].dot(up)).normalize();
  const h2 = new THREE.Vector3().crossVectors(up, h1).normalize();

  // ---- 3D view ----
  let renderer = null;
  try {
    renderer = new THREE.WebGLRenderer({antialias: false, preserveDrawingBuffer: true});
  } catch (e) {
    el('div', {class: 'message'}, view,
       'This browser gives no WebGL, so the 3D view cannot be drawn (' + e.message +
       '); the charts and the summary are on the right.');
    setStatus('error: no WebGL: ' + e.message);
  }
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x101418);
  const camera = new THREE.PerspectiveCamera(50, 1, radius * 1e-3, radius * 200);
  camera.up.copy(up);

  function lineGeometry(points) {
    return new THREE.BufferGeometry().setFromPoints(points);
  }

  // Map points, coloured by height (a viridis-like ramp between the 2nd and 98th percentile).
  if (pointsFlat.length) {
    const n = pointsFlat.length / 3;
    const heights = new Float32Array(n);
    for (let i = 0; i < n; ++i) {
      heights[i] = pointsFlat[3 * i] * up.x + pointsFlat[3 * i + 1] * up.y + pointsFlat[3 * i + 2] * up.z;
    }
    const sorted = Float32Array.from(heights).sort();
    const lo = sorted[Math.floor(0.02 * (n - 1))];
    const hi = sorted[Math.floor(0.98 * (n - 1))];
    const ramp = [[0.27, 0.0, 0.33], [0.23, 0.32, 0.55], [0.13, 0.57, 0.55], [0.37, 0.79, 0.38],
                  [0.99, 0.91, 0.14]];
    const colours = new Float32Array(3 * n);
    for (let i = 0; i < n; ++i) {
      const s = hi > lo ? Math.min(1, Math.max(0, (heights[i] - lo) / (hi - lo))) : 0.5;
      const x = s * (ramp.length - 1);
      const k = Math.min(ramp.length - 2, Math.floor(x));
      const f = x - k;
      for (let c = 0; c < 3; ++c) colours[3 * i + c] = ramp[k][c] * (1 - f) + ramp[k + 1][c] * f;
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(pointsFlat, 3));
    g.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    scene.add(new THREE.Points(g, new THREE.PointsMaterial({size: 2, sizeAttenuation: false,
                                                             vertexColors: true})));
    addLegend(0x5ec962, 'map points by height');
  }
  if (gt.length) {
    scene.add(new THREE.Line(lineGeometry(gt), new THREE.LineBasicMaterial({color: COLOUR_GT})));
    addLegend(COLOUR_GT, 'ground truth');
  }
  // Drawn over the map and the keyframes (no depth test, and in three.js's transparent pass, which
  // comes after the opaque one and the frusta), so that a dense map never hides it.
  function onTop(object, order) {
    object.material.depthTest = false;
    object.material.transparent = true;
    object.renderOrder = order;
    return object;
  }
  if (path.length) {
    scene.add(onTop(new THREE.Line(lineGeometry(path),
                                   new THREE.LineBasicMaterial({color: COLOUR_PATH})), 5));
    addLegend(COLOUR_PATH, 'estimate');
  }

  // A camera frustum (pyramid) at a pose, as line segments appended to `out`. Its depth: 80 % of
  // the median distance between keyframes (frusta side by side, not piled up), within 0.5 % and
  // 2.5 % of the scene's size.
  const spacings = [];
  for (let i = 1; i < keyframes.length; ++i) spacings.push(keyframes[i].distanceTo(keyframes[i - 1]));
  spacings.sort(function (a, b) { return a - b; });
  const medianSpacing = spacings.length ? spacings[spacings.length >> 1] : radius;
  const frustumDepth = Math.min(radius * 0.025, Math.max(radius * 0.005, 0.8 * medianSpacing));
  const aspect = data.aspect || 4 / 3;
  function frustum(position, q, depth, out) {
    const w = depth * 0.5 * aspect, h = depth * 0.5;
    const corners = [[-w, -h], [w, -h], [w, h], [-w, h]].map(function (c) {
      return new THREE.Vector3(c[0], c[1], depth).applyQuaternion(q).add(position);
    });
    for (let i = 0; i < 4; ++i) {
      out.push(position, corners[i], corners[i], corners[(i + 1) % 4]);
    }
  }
  if (keyframes.length) {
    const segments = [];
    for (let i = 0; i < keyframes.length; ++i) frustum(keyframes[i], keyframesQ[i], frustumDepth, segments);
    scene.add(new THREE.LineSegments(lineGeometry(segments),
                                     new THREE.LineBasicMaterial({color: COLOUR_KEYFRAME,
                                                                  transparent: true, opacity: 0.6})));
    addLegend(COLOUR_KEYFRAME, keyframes.length + ' keyframes');
  }
  // Loop edges: closed (the estimator corrected with it) and detected only.
  const loopSegments = {closed: [], detected: []};
  for (const loop of data.loops) {
    loopSegments[loop.closed ? 'closed' : 'detected'].push(new THREE.Vector3().fromArray(loop.a),
                                                           new THREE.Vector3().fromArray(loop.b));
  }
  if (loopSegments.closed.length) {
    scene.add(onTop(new THREE.LineSegments(lineGeometry(loopSegments.closed),
                                           new THREE.LineBasicMaterial({color: COLOUR_LOOP_CLOSED})), 6));
    addLegend(COLOUR_LOOP_CLOSED, (loopSegments.closed.length / 2) + ' loops closed');
  }
  if (loopSegments.detected.length) {
    scene.add(onTop(new THREE.LineSegments(lineGeometry(loopSegments.detected),
                                           new THREE.LineBasicMaterial({color: COLOUR_LOOP_DETECTED})), 6));
    addLegend(COLOUR_LOOP_DETECTED, (loopSegments.detected.length / 2) + ' loops detected, not closed');
  }
  function markers(flat, colour, size, label) {
    if (!flat || !flat.length) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(flat, 3));
    scene.add(onTop(new THREE.Points(g, new THREE.PointsMaterial({color: colour, size: size,
                                                                   sizeAttenuation: false})), 7));
    addLegend(colour, (flat.length / 3) + ' ' + label);
  }
  markers(data.lost.xyz, COLOUR_LOST, 7, 'lost');
  markers(data.relocalised.xyz, COLOUR_RELOCALISED, 9, 'relocalised');

  // The camera marker: a sphere and a frustum, drawn over everything.
  const marker = new THREE.Group();
  const markerMaterial = new THREE.MeshBasicMaterial({color: COLOUR_MARKER, depthTest: false,
                                                      transparent: true});
  const sphere = new THREE.Mesh(new THREE.SphereGeometry(radius * 0.018, 16, 12), markerMaterial);
  sphere.renderOrder = 10;
  marker.add(sphere);
  const markerFrustum = [];
  frustum(new THREE.Vector3(), new THREE.Quaternion(), radius * 0.05, markerFrustum);
  const markerLines = new THREE.LineSegments(
      lineGeometry(markerFrustum),
      new THREE.LineBasicMaterial({color: COLOUR_MARKER, depthTest: false, transparent: true}));
  markerLines.renderOrder = 10;
  marker.add(markerLines);
  marker.visible = path.length > 0;
  scene.add(marker);

  let controls = null;
  function render() {
    if (renderer) renderer.render(scene, camera);
  }
  function resize() {
    if (!renderer) return;
    const w = Math.max(view.clientWidth, 1), h = Math.max(view.clientHeight, 1);
    renderer.setSize(w, h, false);
    renderer.domElement.style.width = w + 'px';
    renderer.domElement.style.height = h + 'px';
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  }
  function lookFrom(direction, distance) {
    camera.position.copy(centre).addScaledVector(direction.clone().normalize(), distance);
    camera.lookAt(centre);
    if (controls) {
      controls.target.copy(centre);
      controls.update();
    }
    render();
  }
  function topView() {
    // Straight down, slightly off the axis so that the orbit controls keep their up.
    lookFrom(up.clone().addScaledVector(h2, -1e-3), radius * 2.3);
  }
  function sideView() { lookFrom(h2.clone().negate(), radius * 2.3); }
  function obliqueView() {
    lookFrom(up.clone().multiplyScalar(0.9).addScaledVector(h2, -1).addScaledVector(h1, -0.5),
             radius * 2.0);
  }
  if (renderer) {
    view.insertBefore(renderer.domElement, legend);
    controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.addEventListener('change', render);
    buttons.Top.onclick = topView;
    buttons.Side.onclick = sideView;
    buttons.Oblique.onclick = obliqueView;
    window.addEventListener('resize', resize);
  }

  // ---- Charts ----
  // A line chart on a canvas: x against each series' y, a cursor at time `cursorT`.
  const chartViews = [];
  function chart(title, note) {
    el('h2', {}, side, title);
    const canvas = el('canvas', {}, side);
    if (note) el('div', {class: 'note'}, side, note);
    return canvas;
  }
  function drawChart(canvas, spec, cursorT) {
    const w = canvas.width = canvas.clientWidth || 420;
    const h = canvas.height = canvas.clientHeight || 150;
    const ctx = canvas.getContext('2d');
    ctx.clearRect(0, 0, w, h);
    const left = 44, right = 8, top = 8, bottom = 20;
    // From 0 up, or (spec.signed) over the values' range, 0 included.
    let yMax = 0, yMin = 0;
    for (const s of spec.series) {
      for (const v of s.y) {
        if (!isFinite(v)) continue;
        if (v > yMax) yMax = v;
        if (spec.signed && v < yMin) yMin = v;
      }
    }
    if (yMax - yMin <= 0) yMax = yMin + 1;
    const xMax = Math.max(tEnd, 1e-9);
    const X = function (t) { return left + (w - left - right) * t / xMax; };
    const Y = function (v) { return h - bottom - (h - top - bottom) * (v - yMin) / (yMax - yMin); };
    ctx.strokeStyle = '#999';
    ctx.beginPath();
    ctx.moveTo(left, top);
    ctx.lineTo(left, h - bottom);
    ctx.lineTo(w - right, h - bottom);
    ctx.stroke();
    ctx.fillStyle = '#555';
    ctx.font = '10px sans-serif';
    ctx.fillText(yMax.toPrecision(3), 2, top + 8);
    ctx.fillText(yMin === 0 ? '0' : yMin.toPrecision(3), 2, h - bottom);
    if (yMin < 0) {
      ctx.strokeStyle = '#ccc';
      ctx.beginPath();
      ctx.moveTo(left, Y(0));
      ctx.lineTo(w - right, Y(0));
      ctx.stroke();
    }
    ctx.fillText('0 s', left, h - 6);
    ctx.fillText(xMax.toFixed(1) + ' s', w - right - 40, h - 6);
    if (spec.bands) {
      // Frames by state: lost (orange) and initialising (grey) under the curves.
      for (let i = 0; i < charts.t.length; ++i) {
        const s = charts.status[i];
        if (s === 1) continue;
        ctx.fillStyle = s === 2 ? 'rgba(255,160,0,0.35)' : 'rgba(128,128,128,0.2)';
        const x0 = X(charts.t[i]);
        const x1 = i + 1 < charts.t.length ? X(charts.t[i + 1]) : x0 + 1;
        ctx.fillRect(x0, top, Math.max(x1 - x0, 1), h - top - bottom);
      }
    }
    if (spec.ticks) {
      ctx.strokeStyle = 'rgba(60,150,255,0.5)';
      ctx.beginPath();
      for (const t of spec.ticks) {
        ctx.moveTo(X(t), h - bottom);
        ctx.lineTo(X(t), h - bottom - 10);
      }
      ctx.stroke();
    }
    let lx = left + 6;
    for (const s of spec.series) {
      ctx.strokeStyle = s.colour;
      ctx.beginPath();
      for (let i = 0; i < s.y.length; ++i) {
        const x = X(s.x[i]), y = Y(s.y[i]);
        if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
      }
      ctx.stroke();
      ctx.fillStyle = s.colour;
      ctx.fillText(s.label, lx, top + 10);
      lx += ctx.measureText(s.label).width + 12;
    }
    if (cursorT !== undefined) {
      ctx.strokeStyle = hex(COLOUR_MARKER);
      ctx.beginPath();
      ctx.moveTo(X(cursorT), top);
      ctx.lineTo(X(cursorT), h - bottom);
      ctx.stroke();
    }
  }
  if (charts.t.length) {
    chartViews.push({canvas: chart('Points per frame', 'Features in the frame, those continuing a track, ' +
                                   'landmarks in the estimator; orange: lost frames, grey: initialising.'),
                     spec: {bands: true, series: [
                       {x: charts.t, y: charts.features, colour: '#888', label: 'features'},
                       {x: charts.t, y: charts.tracked, colour: '#1f77b4', label: 'tracked'},
                       {x: charts.t, y: charts.landmarks, colour: '#2ca02c', label: 'landmarks'}]}});
    const kfT = [], kfCount = [];
    let count = 0;
    for (let i = 0; i < charts.t.length; ++i) {
      count += charts.keyframe[i];
      kfCount.push(count);
      if (charts.keyframe[i]) kfT.push(charts.t[i]);
    }
    chartViews.push({canvas: chart('Keyframe decisions', 'A tick per keyframe; the line counts them.'),
                     spec: {ticks: kfT, series: [{x: charts.t, y: kfCount, colour: '#3c96ff',
                                                  label: 'keyframes so far'}]}});
    chartViews.push({canvas: chart('Time per frame (ms)', 'Frontend and estimator, per frame.'),
                     spec: {series: [{x: charts.t, y: charts.ms, colour: '#d62728', label: 'ms'}]}});
  }
  if (data.error) {
    chartViews.push({canvas: chart('Error along the path (m)',
                                   'Absolute position error of each pose after the alignment (ATE).'),
                     spec: {series: [{x: data.error.t, y: data.error.m, colour: '#9467bd',
                                      label: 'position error'}]}});
    if (data.scale) {
      chartViews.push({canvas: chart('Scale along the path (%)',
                                     'Each segment of the path aligned on its own (Sim(3)): its size ' +
                                     'against the truth\'s, in percent off the run\'s scale. A drifting ' +
                                     'scale shows as steps.'),
                       spec: {signed: true, series: [{x: data.scale.t, y: data.scale.percent,
                                                      colour: '#17becf', label: 'scale off (%)'}]}});
    }
  } else {
    el('h2', {}, side, 'Error along the path');
    el('div', {class: 'note'}, side, 'No ground truth: no error to show.');
  }
  el('h2', {}, side, 'Summary');
  el('pre', {}, side, data.summary_text || '(no summary: a map alone)');
  el('div', {class: 'note'}, side, 'Shown in ' + data.frame_of_reference + '. Map points: ' +
     data.points.shown + ' of ' + data.points.total +
     (data.points.shown < data.points.total ? ' (decimated)' : '') + '.');

  // ---- Time ----
  // The pose at time t: interpolated between the path's poses.
  function poseAt(t) {
    let lo = 0, hi = pathT.length - 1;
    if (t <= pathT[0]) hi = 0;
    else if (t >= pathT[hi]) lo = hi;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (pathT[mid] <= t) lo = mid; else hi = mid;
    }
    const f = hi > lo ? (t - pathT[lo]) / (pathT[hi] - pathT[lo]) : 0;
    const p = path[lo].clone().lerp(path[hi], f);
    const q = pathQ[lo].clone().slerp(pathQ[hi], f);
    return {p: p, q: q};
  }
  function frameAt(t) {
    let best = -1;
    for (let i = 0; i < charts.t.length && charts.t[i] <= t + 1e-6; ++i) best = i;
    return best;
  }
  function setTime(fraction) {
    fraction = Math.min(1, Math.max(0, fraction));
    slider.value = String(Math.round(fraction * 1000));
    const t = fraction * tEnd;
    if (path.length) {
      const pose = poseAt(t);
      marker.position.copy(pose.p);
      marker.quaternion.copy(pose.q);
    }
    const i = frameAt(t);
    const status = i >= 0 ? ['initialising', 'tracking', 'lost'][charts.status[i]] : '';
    timeLabel.textContent = 't = ' + t.toFixed(2) + ' s' +
        (i >= 0 ? ', frame ' + charts.frame[i] + ', ' + status +
                  (charts.keyframe[i] ? ', keyframe' : '') : '');
    for (const c of chartViews) drawChart(c.canvas, c.spec, t);
    render();
  }
  function hashFraction() {
    const m = /(?:^#|&)t=([0-9.]+)/.exec(window.location.hash);
    return m ? parseFloat(m[1]) : 0;
  }
  slider.addEventListener('input', function () { setTime(slider.value / 1000); });
  window.addEventListener('hashchange', function () { setTime(hashFraction()); });
  let playing = false;
  play.onclick = function () {
    playing = !playing;
    play.textContent = playing ? 'Pause' : 'Play';
    let last = null;
    function step(now) {
      if (!playing) return;
      if (last !== null) {
        // The whole run in 20 s.
        const next = slider.value / 1000 + (now - last) / 20000;
        if (next >= 1) {
          playing = false;
          play.textContent = 'Play';
        }
        setTime(next);
      }
      last = now;
      requestAnimationFrame(step);
    }
    if (playing) {
      if (slider.value >= 1000) setTime(0);
      requestAnimationFrame(step);
    }
  };

  obliqueView();
  resize();
  setTime(hashFraction());
  if (renderer) setStatus('ready');
})();

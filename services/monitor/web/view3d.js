// The 3-D view: sensed centreline as a tube, markers, tip, target tube,
// truth line, the cameras' frusta and the base axes, with three.js r111
// (global THREE, THREE.OrbitControls). World frame in mm, z up (the
// calibration board's normal). Messages only store the latest data;
// frame() builds geometry and renders from requestAnimationFrame, and only
// when something changed, so 30 Hz shapes never pile up.
'use strict';

(function () {
  const COLORS = {
    sensed: 0x4fc3f7,
    invalid: 0xe57373,
    target: 0xff9800,
    truth: 0x9e9e9e,
    marker: 0x00e5ff,
    tip: 0xff40ff,
    frusta: [0x81c784, 0xffd54f, 0x64b5f6, 0xf06292, 0xba68c8, 0x4db6ac],
  };
  const TUBE_RADIUS = 3.0;        // the rig's tube radius, mm
  const TARGET_RADIUS = 3.6;      // a little wider, so the sensed tube shows through it
  const DEFAULT_DIRECTION = [0.55, -0.8, 0.42];

  function setAttr(geometry, name, attribute) {
    if (geometry.setAttribute) geometry.setAttribute(name, attribute);
    else geometry.addAttribute(name, attribute);
  }

  function toVectors(points) {
    return points.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
  }

  // Consecutive duplicate points make CatmullRomCurve3 produce NaN tangents.
  function dedupe(vectors) {
    const out = [];
    for (const v of vectors) {
      if (!out.length || out[out.length - 1].distanceToSquared(v) > 1e-8) out.push(v);
    }
    return out;
  }

  function tubeGeometry(points, radius) {
    const vectors = dedupe(toVectors(points));
    if (vectors.length < 2) return null;
    const curve = new THREE.CatmullRomCurve3(vectors, false, 'centripetal');
    const segments = Math.min(256, Math.max(16, vectors.length * 3));
    const Tube = THREE.TubeBufferGeometry || THREE.TubeGeometry;
    return new Tube(curve, segments, radius, 12, false);
  }

  function labelSprite(text, color) {
    const canvas = document.createElement('canvas');
    canvas.width = 128;
    canvas.height = 32;
    const ctx = canvas.getContext('2d');
    ctx.font = 'bold 24px system-ui, sans-serif';
    ctx.textBaseline = 'middle';
    ctx.fillStyle = '#' + color.toString(16).padStart(6, '0');
    ctx.fillText(text, 4, 16, 120);
    const texture = new THREE.CanvasTexture(canvas);
    // A constant size on screen (about 13 px high in a 400 px view).
    const material = new THREE.SpriteMaterial({ map: texture, depthTest: false, transparent: true, sizeAttenuation: false });
    const sprite = new THREE.Sprite(material);
    sprite.scale.set(0.094, 0.0234, 1);
    if (sprite.center) sprite.center.set(0, 0);
    return sprite;
  }

  function rendererName(gl) {
    try {
      const ext = gl.getExtension('WEBGL_debug_renderer_info');
      return String(ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER));
    } catch (e) {
      return '';
    }
  }

  // The renderer's name from a throwaway context ('' when there is none).
  function probeRenderer() {
    try {
      const gl = document.createElement('canvas').getContext('webgl');
      if (!gl) return '';
      const name = rendererName(gl);
      const lose = gl.getExtension('WEBGL_lose_context');
      if (lose) lose.loseContext();
      return name;
    } catch (e) {
      return '';
    }
  }

  function disposeObject(object) {
    object.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      if (o.material) {
        if (o.material.map) o.material.map.dispose();
        o.material.dispose();
      }
    });
  }

  class View3D {
    constructor(canvas, messageElement) {
      this.canvas = canvas;
      this.messageElement = messageElement;
      this.ok = false;
      this.failure = '';
      this.dirty = true;
      this.renders = 0;
      this.layers = { target: true, truth: false, markers: true, frusta: true, voxels: false };
      this.pending = { shape: null, target: undefined, truth: null, cameras: null, voxels: null };
      this.fittedToShape = false;
      this.fittedToCameras = false;
      this.frustumPoints = [];
      this.shapePoints = [];
      this.targetPoints = [];
      this.reachPoints = [];
      try {
        this.init();
        this.ok = true;
      } catch (e) {
        this.fail(e && e.message ? e.message : String(e));
      }
    }

    fail(reason) {
      this.ok = false;
      this.failure = reason;
      if (this.messageElement) {
        this.messageElement.textContent =
          '3-D view unavailable: ' + reason + '\nThe rest of the monitor works without it.';
        this.messageElement.hidden = false;
      }
    }

    init() {
      // (OrbitControls.js defines an empty THREE when three.min.js failed to load.)
      if (typeof THREE === 'undefined' || typeof THREE.WebGLRenderer !== 'function') {
        throw new Error('three.js did not load (vendor/three.min.js)');
      }
      // A software rasteriser (SwiftShader: no GPU, as in headless tests) gets
      // no antialiasing, which costs it most of its time, and a capped render rate.
      const probed = probeRenderer();
      this.software = /swiftshader|llvmpipe|softpipe|software/i.test(probed);
      let renderer;
      try {
        renderer = new THREE.WebGLRenderer({ canvas: this.canvas, antialias: !this.software, preserveDrawingBuffer: true });
      } catch (e) {
        throw new Error('WebGL is not available in this browser (' + (e && e.message ? e.message : e) + ')');
      }
      this.renderer = renderer;
      renderer.setPixelRatio(window.devicePixelRatio || 1);
      renderer.setClearColor(0x0b0e12, 1);
      // Data-driven renders: every shape on a GPU, at most 4 per second in software.
      this.rendererName = rendererName(renderer.getContext()) || probed;
      // (On a 2-core machine without a GPU, the browser shares the CPU with the
      // pipeline it watches: 4 renders a second leave it most of the machine.)
      this.minIntervalMs = this.software ? 250 : 0;
      this.lastRender = -Infinity;
      this.canvas.addEventListener('webglcontextlost', (event) => {
        event.preventDefault();
        this.fail('the WebGL context was lost');
      });

      const scene = (this.scene = new THREE.Scene());
      const camera = (this.camera = new THREE.PerspectiveCamera(40, 1, 1, 20000));
      camera.up.set(0, 0, 1);
      camera.position.set(420, -600, 380);
      scene.add(camera);
      scene.add(new THREE.HemisphereLight(0xffffff, 0x303840, 0.75));
      const headlight = new THREE.DirectionalLight(0xffffff, 0.6);
      headlight.position.set(0.3, 0.6, 1);
      camera.add(headlight);

      if (THREE.OrbitControls) {
        this.controls = new THREE.OrbitControls(camera, this.canvas);
        this.controls.screenSpacePanning = true;
        this.controls.target.set(0, 0, 80);
        this.controls.addEventListener('change', () => { this.dirty = true; this.interacting = true; });
        this.controls.update();
      } else {
        camera.lookAt(0, 0, 80);
      }

      // Base frame and a floor grid on the world's x-y plane.
      scene.add(new THREE.AxesHelper(50));
      const grid = new THREE.GridHelper(400, 16, 0x33404d, 0x1d252e);
      grid.rotation.x = Math.PI / 2;
      scene.add(grid);

      const sensedMaterial = new THREE.MeshStandardMaterial({ color: COLORS.sensed, roughness: 0.45, metalness: 0.1 });
      this.sensed = new THREE.Mesh(new THREE.BufferGeometry(), sensedMaterial);
      this.sensed.visible = false;
      scene.add(this.sensed);

      const targetMaterial = new THREE.MeshStandardMaterial({
        color: COLORS.target, emissive: 0x5a2a00, roughness: 0.6, transparent: true, opacity: 0.3, depthWrite: false,
      });
      this.target = new THREE.Mesh(new THREE.BufferGeometry(), targetMaterial);
      this.target.visible = false;
      this.target.renderOrder = 2;
      scene.add(this.target);
      this.targetTip = new THREE.Mesh(new THREE.SphereBufferGeometry(6, 12, 8),
        new THREE.MeshBasicMaterial({ color: COLORS.target, wireframe: true }));
      this.targetTip.visible = false;
      scene.add(this.targetTip);

      this.truth = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: COLORS.truth }));
      this.truth.visible = false;
      scene.add(this.truth);

      // The visual hull: one point per occupied voxel, its edge long.
      this.voxels = new THREE.Points(new THREE.BufferGeometry(),
        new THREE.PointsMaterial({ color: 0x7d8a99, size: 1, sizeAttenuation: true, transparent: true, opacity: 0.55 }));
      this.voxels.visible = false;
      scene.add(this.voxels);

      this.markerGeometry = new THREE.SphereBufferGeometry(3.2, 12, 8);
      this.markerMaterial = new THREE.MeshStandardMaterial({ color: COLORS.marker, emissive: 0x004a52 });
      this.markers = new THREE.Group();
      scene.add(this.markers);
      this.tip = new THREE.Mesh(new THREE.SphereBufferGeometry(4.5, 16, 12),
        new THREE.MeshStandardMaterial({ color: COLORS.tip, emissive: 0x4a004a }));
      this.tip.visible = false;
      scene.add(this.tip);

      this.frusta = new THREE.Group();
      scene.add(this.frusta);
      this.size = [0, 0];
    }

    // Latest data; built on the next frame().
    setShape(shape) { this.pending.shape = shape; this.dirty = true; }
    setTruth(truth) { this.pending.truth = truth; this.dirty = true; }
    setVoxels(voxels) { this.pending.voxels = voxels; this.dirty = true; }
    setTarget(target) { this.pending.target = target; this.dirty = true; }
    setCameras(cameras) { this.pending.cameras = cameras; this.dirty = true; }
    setLayer(name, on) {
      this.layers[name] = !!on;
      this.applyLayers();
      this.dirty = true;
    }

    applyLayers() {
      if (!this.ok) return;
      this.markers.visible = this.layers.markers;
      this.frusta.visible = this.layers.frusta;
      this.truth.visible = this.layers.truth && this.truthHasData === true;
      this.voxels.visible = this.layers.voxels && this.voxelsHaveData === true;
      this.target.visible = this.layers.target && this.targetHasTube === true;
      this.targetTip.visible = this.layers.target && this.targetHasTip === true;
    }

    buildShape(shape) {
      const geometry = shape.centerline.length >= 2 ? tubeGeometry(shape.centerline, TUBE_RADIUS) : null;
      if (geometry) {
        this.sensed.geometry.dispose();
        this.sensed.geometry = geometry;
        this.sensed.visible = true;
        this.shapePoints = shape.centerline;
      }
      // An invalid shape keeps the last tube (if its own has no points), drawn red.
      this.sensed.material.color.setHex(shape.valid ? COLORS.sensed : COLORS.invalid);

      const markers = this.markers.children;
      while (markers.length < shape.markers.length) {
        this.markers.add(new THREE.Mesh(this.markerGeometry, this.markerMaterial));
      }
      for (let i = 0; i < markers.length; i++) {
        const m = markers[i];
        if (i < shape.markers.length) {
          const p = shape.markers[i];
          m.position.set(p[0], p[1], p[2]);
          m.visible = true;
        } else {
          m.visible = false;
        }
      }
      if (shape.tip) {
        this.tip.position.set(shape.tip[0], shape.tip[1], shape.tip[2]);
        this.tip.visible = true;
      } else {
        this.tip.visible = false;
      }
      if (!this.fittedToShape && geometry) {
        // The first fit covers where the tube can reach (it moves after this),
        // not only where it is now.
        this.fittedToShape = true;
        let length = shape.length;
        if (!(length > 0)) {
          length = 0;
          for (let i = 1; i < shape.centerline.length; i++) {
            const a = shape.centerline[i - 1], b = shape.centerline[i];
            length += Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
          }
        }
        const base = shape.centerline[0];
        const r = 0.6 * length;
        this.reachPoints = [];
        for (let i = 0; i < 8; i++) {
          this.reachPoints.push([base[0] + (i & 1 ? r : -r), base[1] + (i & 2 ? r : -r), base[2] + (i & 4 ? length : 0)]);
        }
        this.fit(false, true, true);
        this.reachPoints = [];
      }
    }

    buildTarget(target) {
      this.targetHasTube = false;
      this.targetHasTip = false;
      this.targetPoints = [];
      if (target && target.centerline && target.centerline.length >= 2) {
        const geometry = tubeGeometry(target.centerline, TARGET_RADIUS);
        if (geometry) {
          this.target.geometry.dispose();
          this.target.geometry = geometry;
          this.targetHasTube = true;
          this.targetPoints = target.centerline;
        }
      }
      if (target && target.tip) {
        this.targetTip.position.set(target.tip[0], target.tip[1], target.tip[2]);
        this.targetHasTip = true;
      }
    }

    buildVoxels(voxels) {
      this.voxelsHaveData = false;
      if (!voxels || voxels.points.length < 3) return;
      const geometry = new THREE.BufferGeometry();
      setAttr(geometry, 'position', new THREE.BufferAttribute(Float32Array.from(voxels.points), 3));
      this.voxels.geometry.dispose();
      this.voxels.geometry = geometry;
      this.voxels.material.size = voxels.voxel_size;
      this.voxelsHaveData = true;
    }

    buildTruth(truth) {
      this.truthHasData = false;
      if (!truth || truth.centerline.length < 2) return;
      const positions = new Float32Array(truth.centerline.length * 3);
      truth.centerline.forEach((p, i) => positions.set(p, i * 3));
      const geometry = new THREE.BufferGeometry();
      setAttr(geometry, 'position', new THREE.BufferAttribute(positions, 3));
      this.truth.geometry.dispose();
      this.truth.geometry = geometry;
      this.truthHasData = true;
    }

    buildCameras(cameras) {
      for (const child of this.frusta.children.slice()) {
        this.frusta.remove(child);
        disposeObject(child);
      }
      this.frustumPoints = [];
      cameras.forEach((camera, index) => {
        if (!camera.frustum) return;
        const [apex, a, b, c, d] = camera.frustum;
        const color = COLORS.frusta[index % COLORS.frusta.length];
        const segments = [apex, a, apex, b, apex, c, apex, d, a, b, b, c, c, d, d, a];
        const positions = new Float32Array(segments.length * 3);
        segments.forEach((p, i) => positions.set(p, i * 3));
        const geometry = new THREE.BufferGeometry();
        setAttr(geometry, 'position', new THREE.BufferAttribute(positions, 3));
        const lines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color }));
        const group = new THREE.Group();
        group.add(lines);
        // The image's top edge, thicker in effect: a small triangle above it.
        const mid = [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2];
        const up = [(a[0] - d[0]) * 0.15, (a[1] - d[1]) * 0.15, (a[2] - d[2]) * 0.15];
        const tri = [a, [mid[0] + up[0], mid[1] + up[1], mid[2] + up[2]], [mid[0] + up[0], mid[1] + up[1], mid[2] + up[2]], b];
        const triPositions = new Float32Array(12);
        tri.forEach((p, i) => triPositions.set(p, i * 3));
        const triGeometry = new THREE.BufferGeometry();
        setAttr(triGeometry, 'position', new THREE.BufferAttribute(triPositions, 3));
        group.add(new THREE.LineSegments(triGeometry, new THREE.LineBasicMaterial({ color })));
        const label = labelSprite(camera.name, color);
        label.position.set(apex[0], apex[1], apex[2]);
        group.add(label);
        this.frusta.add(group);
        this.frustumPoints.push(apex, a, b, c, d);
      });
      if (!this.fittedToShape && !this.fittedToCameras && this.frustumPoints.length) {
        this.fittedToCameras = true;
        this.fit(true, true);
      }
    }

    // Points the fit covers: the shape, the target, the base and, for
    // `withCameras`, the cameras' frusta.
    fit(withCameras, defaultDirection, withReach) {
      if (!this.ok) return;
      const points = [[0, 0, 0]].concat(this.shapePoints, this.targetPoints, withCameras ? this.frustumPoints : [],
        withReach && this.reachPoints ? this.reachPoints : []);
      const box = new THREE.Box3().setFromPoints(toVectors(points));
      const center = box.getCenter(new THREE.Vector3());
      const camera = this.camera;
      const target = this.controls ? this.controls.target : new THREE.Vector3();
      let direction;
      if (defaultDirection || !this.controls) {
        direction = new THREE.Vector3().fromArray(DEFAULT_DIRECTION).normalize();
      } else {
        direction = camera.position.clone().sub(target).normalize();
      }
      // The distance along `direction` at which every point is in view.
      const right = new THREE.Vector3().crossVectors(camera.up, direction).normalize();
      const up = new THREE.Vector3().crossVectors(direction, right).normalize();
      const tanV = Math.tan((camera.fov * Math.PI) / 360) / 1.08; // 8 % margin
      const tanH = tanV * camera.aspect;
      let distance = withCameras ? 200 : 150;
      const d = new THREE.Vector3();
      for (const p of points) {
        d.set(p[0], p[1], p[2]).sub(center);
        const z = d.dot(direction);
        distance = Math.max(distance, z + Math.abs(d.dot(right)) / tanH, z + Math.abs(d.dot(up)) / tanV);
      }
      target.copy(center);
      camera.position.copy(center).addScaledVector(direction, distance);
      camera.near = Math.max(0.5, distance / 200);
      camera.far = distance * 20 + 4000;
      camera.updateProjectionMatrix();
      if (this.controls) this.controls.update();
      else camera.lookAt(center);
      this.dirty = true;
    }

    resize() {
      const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
      if (w === this.size[0] && h === this.size[1]) return;
      this.size = [w, h];
      if (w < 2 || h < 2) return;
      this.renderer.setSize(w, h, false);
      this.camera.aspect = w / h;
      this.camera.updateProjectionMatrix();
      this.dirty = true;
    }

    // Called every animation frame; returns true when it rendered.
    frame() {
      if (!this.ok) return false;
      const now = performance.now();
      if (!this.interacting && now - this.lastRender < this.minIntervalMs) return false;
      this.interacting = false;
      this.resize();
      const p = this.pending;
      if (p.cameras) { this.buildCameras(p.cameras); p.cameras = null; }
      if (p.target !== undefined) { this.buildTarget(p.target); p.target = undefined; }
      if (p.truth) { this.buildTruth(p.truth); p.truth = null; }
      if (p.voxels) { this.buildVoxels(p.voxels); p.voxels = null; }
      if (p.shape) { this.buildShape(p.shape); p.shape = null; }
      if (!this.dirty || this.size[0] < 2 || this.size[1] < 2) return false;
      this.applyLayers();
      this.renderer.render(this.scene, this.camera);
      this.lastRender = now;
      this.renders++;
      this.dirty = false;
      return true;
    }

    stats() {
      if (!this.ok) return { ok: false, failure: this.failure };
      const info = this.renderer.info;
      return {
        ok: true, renders: this.renders, geometries: info.memory.geometries, textures: info.memory.textures,
        renderer: this.rendererName, software: this.software,
      };
    }
  }

  window.ShapesenseView3D = View3D;
})();

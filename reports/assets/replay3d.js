// fullarm report.html 3D replay: bundled with three.js by esbuild at build time and inlined
// into every report that holds a replay (this file itself must not contain script tags).
//
// The replays live in the JSON script element with id "fullarm-report-data", under "replays"
// (layout in docs/reports.md). Every element with a data-replay3d attribute names its replay;
// once drawn it gets data-rendered="true" (or "error", with the message shown in its place).
// The page's state is exposed for checks as window.fullarmReplays[id].state(): the shown
// frame, its time, and per link whether it penetrates and the colour it is drawn in.
import {
  AmbientLight,
  BufferAttribute,
  BufferGeometry,
  CapsuleGeometry,
  Color,
  DirectionalLight,
  LineBasicMaterial,
  LineSegments,
  Mesh,
  MeshLambertMaterial,
  PerspectiveCamera,
  Points,
  PointsMaterial,
  SRGBColorSpace,
  Quaternion,
  Scene,
  Vector3,
  WebGLRenderer,
  Box3,
  DoubleSide,
} from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const kLinkColor = "#4a78b5";
const kPenetratingColor = "#d62728";
const kSceneColor = "#b8b2a7";
const kSpeeds = [0.1, 0.25, 0.5, 1, 2, 4];

function decode(base64) {
  const binary = atob(base64);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

// Force colour (sRGB): green (no force) through yellow to red (force_scale_n and above).
function forceColor(force, scale, color) {
  const x = Math.max(0, Math.min(1, force / scale));
  if (x < 0.5) color.setRGB(0.17 + 1.66 * x, 0.63 + 0.58 * x, 0.17 - 0.22 * x, SRGBColorSpace);
  else color.setRGB(1.0, 0.92 - 1.7 * (x - 0.5), 0.06, SRGBColorSpace);
  return color;
}

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined) node.textContent = text;
  return node;
}

function formatTime(t) {
  return t.toFixed(3) + " s";
}

class Replay {
  constructor(root, data) {
    this.root = root;
    this.data = data;
    this.frameCount = data.frame_count;
    this.links = data.links;
    this.joints = data.joints;
    this.times = new Float64Array(decode(data.t_f64));
    this.segments = new Float32Array(decode(data.segments_f32));
    this.penetrating = new Uint8Array(decode(data.penetrating_u8));
    this.torques = new Float32Array(decode(data.torques_f32));
    this.minimaOffsets = new Uint32Array(decode(data.minima_offsets_u32));
    this.minima = new Float32Array(decode(data.minima_f32));
    this.frame = -1;
    this.playing = false;
    this.speed = 1;
    this.buildDom();
    this.buildScene();
    this.show(0);
  }

  buildDom() {
    const root = this.root;
    root.textContent = "";
    const row = element("div", "replay3d-row");
    this.view = element("div", "replay3d-view");
    this.canvas = element("canvas", "replay3d-canvas");
    this.canvas.setAttribute("aria-label", "3D view of the arm and the scene");
    this.view.appendChild(this.canvas);
    row.appendChild(this.view);

    const bars = element("div", "replay3d-bars");
    bars.appendChild(element("div", "replay3d-bars-title", "Joint torque [N·m]"));
    this.barFills = [];
    this.barValues = [];
    for (const name of this.joints) {
      const bar = element("div", "replay3d-bar");
      bar.appendChild(element("span", "replay3d-bar-name", name));
      const track = element("span", "replay3d-bar-track");
      const fill = element("span", "replay3d-bar-fill");
      track.appendChild(fill);
      bar.appendChild(track);
      const value = element("span", "replay3d-bar-value");
      bar.appendChild(value);
      bars.appendChild(bar);
      this.barFills.push(fill);
      this.barValues.push(value);
    }
    bars.appendChild(element("div", "replay3d-bars-scale",
                             "Bars full scale ±" + this.data.torque_scale_nm.toPrecision(3) + " N·m"));
    const legend = element("div", "replay3d-legend");
    legend.appendChild(element("div", "replay3d-legend-title", "Minima: force"));
    legend.appendChild(element("div", "replay3d-legend-ramp"));
    legend.appendChild(element("div", "replay3d-legend-scale",
                               "0 to " + this.data.force_scale_n.toPrecision(3) + " N"));
    const swatch = element("div", "replay3d-legend-item");
    const box = element("span", "replay3d-swatch");
    box.style.background = kPenetratingColor;
    swatch.appendChild(box);
    swatch.appendChild(document.createTextNode(" link touching the scene"));
    legend.appendChild(swatch);
    bars.appendChild(legend);
    row.appendChild(bars);
    root.appendChild(row);

    const controls = element("div", "replay3d-controls");
    this.playButton = element("button", "replay3d-play", "Play");
    this.playButton.type = "button";
    this.playButton.addEventListener("click", () => this.setPlaying(!this.playing));
    controls.appendChild(this.playButton);
    const speedLabel = element("label", "replay3d-speed", "Speed ");
    this.speedSelect = element("select");
    for (const speed of kSpeeds) {
      const option = element("option", "", speed + "×");
      option.value = String(speed);
      if (speed === 1) option.selected = true;
      this.speedSelect.appendChild(option);
    }
    this.speedSelect.addEventListener("change", () => { this.speed = Number(this.speedSelect.value); });
    speedLabel.appendChild(this.speedSelect);
    controls.appendChild(speedLabel);
    const sliderBox = element("div", "replay3d-slider-box");
    this.slider = element("input", "replay3d-slider");
    this.slider.type = "range";
    this.slider.min = "0";
    this.slider.max = String(this.frameCount - 1);
    this.slider.step = "1";
    this.slider.value = "0";
    this.slider.setAttribute("aria-label", "Time");
    this.slider.addEventListener("input", () => {
      this.setPlaying(false);
      this.show(Number(this.slider.value));
    });
    sliderBox.appendChild(this.slider);
    const track = element("div", "replay3d-events");
    const t0 = this.times[0];
    const span = Math.max(this.times[this.frameCount - 1] - t0, 1e-9);
    for (const event of this.data.events) {
      const mark = element("button", "replay3d-event" + (event.trip ? " trip" : ""));
      mark.type = "button";
      mark.title = formatTime(event.t_s) + ": " + event.label;
      mark.setAttribute("aria-label", mark.title);
      mark.style.left = (100 * Math.max(0, Math.min(1, (event.t_s - t0) / span))) + "%";
      mark.addEventListener("click", () => {
        this.setPlaying(false);
        this.show(this.frameAt(event.t_s));
      });
      track.appendChild(mark);
    }
    sliderBox.appendChild(track);
    controls.appendChild(sliderBox);
    this.timeLabel = element("span", "replay3d-time");
    controls.appendChild(this.timeLabel);
    root.appendChild(controls);
    this.eventLabel = element("div", "replay3d-event-label");
    root.appendChild(this.eventLabel);
  }

  buildScene() {
    const renderer = new WebGLRenderer({ canvas: this.canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setClearColor(0xffffff, 1);
    this.renderer = renderer;
    const scene = new Scene();
    this.scene = scene;
    scene.add(new AmbientLight(0xffffff, 1.2));
    const sun = new DirectionalLight(0xffffff, 1.8);
    sun.position.set(1, -2, 3);
    scene.add(sun);

    const sceneMaterial = new MeshLambertMaterial({
      color: kSceneColor, transparent: true, opacity: 0.55, side: DoubleSide, depthWrite: false });
    for (const mesh of this.data.meshes) {
      const q = new Uint16Array(decode(mesh.positions_u16));
      const positions = new Float32Array(q.length);
      for (let i = 0; i < q.length; ++i) positions[i] = mesh.origin_m[i % 3] + q[i] * mesh.scale_m[i % 3];
      const geometry = new BufferGeometry();
      geometry.setAttribute("position", new BufferAttribute(positions, 3));
      geometry.setIndex(new BufferAttribute(new Uint32Array(decode(mesh.indices_u32)), 1));
      geometry.computeVertexNormals();
      const object = new Mesh(geometry, sceneMaterial);
      object.name = mesh.name;
      object.renderOrder = 1;
      scene.add(object);
    }

    // One capsule per link; its segment length is fixed (a rigid link), its pose per frame.
    this.linkMeshes = [];
    this.linkColors = [];
    for (let l = 0; l < this.links.length; ++l) {
      const s = this.segment(0, l);
      const length = Math.hypot(s[3] - s[0], s[4] - s[1], s[5] - s[2]);
      const geometry = new CapsuleGeometry(this.links[l].radius_m, Math.max(length, 1e-6), 8, 24);
      const material = new MeshLambertMaterial({ color: kLinkColor });
      const mesh = new Mesh(geometry, material);
      mesh.name = this.links[l].name;
      scene.add(mesh);
      this.linkMeshes.push(mesh);
      this.linkColors.push(kLinkColor);
    }
    // The camera frames the arm over the whole replay, not the (possibly large) scene.
    const armBounds = new Box3();
    for (let f = 0; f < this.frameCount; ++f) {
      for (let l = 0; l < this.links.length; ++l) {
        const s = this.segment(f, l);
        armBounds.expandByPoint(new Vector3(s[0], s[1], s[2]));
        armBounds.expandByPoint(new Vector3(s[3], s[4], s[5]));
      }
    }

    let maxMinima = 1;
    for (let f = 0; f < this.frameCount; ++f) {
      maxMinima = Math.max(maxMinima, this.minimaOffsets[f + 1] - this.minimaOffsets[f]);
    }
    const lineGeometry = new BufferGeometry();
    this.linePositions = new Float32Array(maxMinima * 6);
    this.lineColors = new Float32Array(maxMinima * 6);
    lineGeometry.setAttribute("position", new BufferAttribute(this.linePositions, 3));
    lineGeometry.setAttribute("color", new BufferAttribute(this.lineColors, 3));
    lineGeometry.setDrawRange(0, 0);
    this.lines = new LineSegments(lineGeometry, new LineBasicMaterial({ vertexColors: true, depthTest: false }));
    this.lines.frustumCulled = false;
    this.lines.renderOrder = 2;
    scene.add(this.lines);
    // The object end of each minimum as a dot, so that a short line still shows.
    const dotGeometry = new BufferGeometry();
    this.dotPositions = new Float32Array(maxMinima * 3);
    this.dotColors = new Float32Array(maxMinima * 3);
    dotGeometry.setAttribute("position", new BufferAttribute(this.dotPositions, 3));
    dotGeometry.setAttribute("color", new BufferAttribute(this.dotColors, 3));
    dotGeometry.setDrawRange(0, 0);
    this.dots = new Points(dotGeometry, new PointsMaterial({
      vertexColors: true, size: 7, sizeAttenuation: false, depthTest: false }));
    this.dots.frustumCulled = false;
    this.dots.renderOrder = 3;
    scene.add(this.dots);

    const camera = new PerspectiveCamera(40, 1, 0.01, 100);
    camera.up.set(0, 0, 1);
    const center = armBounds.getCenter(new Vector3());
    const radius = Math.max(armBounds.getSize(new Vector3()).length() / 2, 0.3);
    const direction = new Vector3(1.3, -1.8, 0.9).normalize();
    camera.position.copy(center).addScaledVector(direction, radius * 2.6);
    camera.lookAt(center);
    this.camera = camera;
    this.controls = new OrbitControls(camera, this.canvas);
    this.controls.target.copy(center);
    this.controls.addEventListener("change", () => this.render());
    this.controls.update();

    this.resize();
    if (typeof ResizeObserver !== "undefined") {
      new ResizeObserver(() => { this.resize(); this.render(); }).observe(this.view);
    }
  }

  resize() {
    const width = Math.max(this.view.clientWidth, 200);
    const height = Math.max(this.view.clientHeight, 200);
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  segment(frame, link) {
    const base = (frame * this.links.length + link) * 6;
    return this.segments.subarray(base, base + 6);
  }

  frameAt(t) {
    let low = 0;
    let high = this.frameCount - 1;
    while (low < high) {
      const mid = (low + high + 1) >> 1;
      if (this.times[mid] <= t) low = mid;
      else high = mid - 1;
    }
    return low;
  }

  show(frame) {
    frame = Math.max(0, Math.min(this.frameCount - 1, frame | 0));
    this.frame = frame;
    const yAxis = new Vector3(0, 1, 0);
    const from = new Vector3();
    const to = new Vector3();
    const direction = new Vector3();
    const rotation = new Quaternion();
    for (let l = 0; l < this.links.length; ++l) {
      const s = this.segment(frame, l);
      from.set(s[0], s[1], s[2]);
      to.set(s[3], s[4], s[5]);
      const mesh = this.linkMeshes[l];
      mesh.position.copy(from).add(to).multiplyScalar(0.5);
      direction.copy(to).sub(from);
      if (direction.lengthSq() > 1e-12) rotation.setFromUnitVectors(yAxis, direction.normalize());
      else rotation.identity();
      mesh.quaternion.copy(rotation);
      const touching = this.penetrating[frame * this.links.length + l] !== 0;
      this.linkColors[l] = touching ? kPenetratingColor : kLinkColor;
      mesh.material.color.set(this.linkColors[l]);
    }

    const first = this.minimaOffsets[frame];
    const count = this.minimaOffsets[frame + 1] - first;
    const color = new Color();
    for (let m = 0; m < count; ++m) {
      const src = (first + m) * 7;
      for (let k = 0; k < 6; ++k) this.linePositions[m * 6 + k] = this.minima[src + k];
      forceColor(this.minima[src + 6], this.data.force_scale_n, color);
      for (let v = 0; v < 2; ++v) {
        this.lineColors[m * 6 + v * 3] = color.r;
        this.lineColors[m * 6 + v * 3 + 1] = color.g;
        this.lineColors[m * 6 + v * 3 + 2] = color.b;
      }
      for (let k = 0; k < 3; ++k) {
        this.dotPositions[m * 3 + k] = this.minima[src + 3 + k];
        this.dotColors[m * 3 + k] = this.lineColors[m * 6 + k];
      }
    }
    for (const object of [this.lines, this.dots]) {
      const geometry = object.geometry;
      geometry.setDrawRange(0, object === this.lines ? count * 2 : count);
      geometry.attributes.position.needsUpdate = true;
      geometry.attributes.color.needsUpdate = true;
    }

    const scale = this.data.torque_scale_nm;
    for (let j = 0; j < this.joints.length; ++j) {
      const tau = this.torques[frame * this.joints.length + j];
      const x = Math.max(-1, Math.min(1, tau / scale));
      const fill = this.barFills[j];
      fill.style.left = (x < 0 ? 50 + 50 * x : 50) + "%";
      fill.style.width = (50 * Math.abs(x)) + "%";
      fill.classList.toggle("negative", x < 0);
      this.barValues[j].textContent = tau.toFixed(2);
    }

    const t = this.times[frame];
    this.slider.value = String(frame);
    this.timeLabel.textContent = formatTime(t) + " (" + (frame + 1) + "/" + this.frameCount + ")";
    const recent = this.data.events.filter((event) => event.t_s <= t);
    this.eventLabel.textContent = recent.length > 0
      ? "Last supervisor event: " + formatTime(recent[recent.length - 1].t_s) + " " + recent[recent.length - 1].label
      : "No supervisor event yet";
    this.root.setAttribute("data-frame", String(frame));
    this.render();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }

  setPlaying(playing) {
    if (playing === this.playing) return;
    this.playing = playing;
    this.playButton.textContent = playing ? "Pause" : "Play";
    if (!playing) return;
    if (this.frame >= this.frameCount - 1) this.show(0);
    let clock = this.times[this.frame];
    let last = performance.now();
    const step = (now) => {
      if (!this.playing) return;
      clock += ((now - last) / 1000) * this.speed;
      last = now;
      const frame = this.frameAt(clock);
      if (frame !== this.frame) this.show(frame);
      if (frame >= this.frameCount - 1) {
        this.setPlaying(false);
        return;
      }
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
  }

  state() {
    const penetrating = [];
    for (let l = 0; l < this.links.length; ++l) {
      penetrating.push(this.penetrating[this.frame * this.links.length + l] !== 0);
    }
    return {
      frame: this.frame,
      frameCount: this.frameCount,
      t_s: this.times[this.frame],
      links: this.links.map((link) => link.name),
      penetrating,
      linkColors: this.linkMeshes.map((mesh) => "#" + mesh.material.color.getHexString()),
      penetratingColor: kPenetratingColor,
      minima: this.minimaOffsets[this.frame + 1] - this.minimaOffsets[this.frame],
      times: Array.from(this.times),
    };
  }
}

function fail(root, message) {
  root.setAttribute("data-rendered", "error");
  root.textContent = "";
  const note = element("p", "chart-error", "3D replay not drawn: " + message);
  root.appendChild(note);
  console.error("fullarm report: replay " + root.getAttribute("data-replay3d") + ": " + message);
}

function start() {
  const roots = document.querySelectorAll("[data-replay3d]");
  let replays;
  try {
    replays = JSON.parse(document.getElementById("fullarm-report-data").textContent).replays || {};
  } catch (error) {
    roots.forEach((root) => fail(root, "bad replay data: " + error));
    return;
  }
  window.fullarmReplays = {};
  roots.forEach((root) => {
    const id = root.getAttribute("data-replay3d");
    const data = replays[id];
    if (!data) {
      fail(root, "no replay data for " + id);
      return;
    }
    try {
      const replay = new Replay(root, data);
      window.fullarmReplays[id] = {
        state: () => replay.state(),
        show: (frame) => replay.show(frame),
        play: (playing) => replay.setPlaying(playing),
      };
      root.setAttribute("data-rendered", "true");
    } catch (error) {
      fail(root, String(error && error.message ? error.message : error));
    }
  });
}

if (document.readyState === "loading") {
  document.addEventListener("DOMContentLoaded", start);
} else {
  start();
}

// The scene of an hrc session drawn in the browser from the states the display node pushes.
// World: y east (m), z up (m), seen from the viewer; the page fits the box of every reachable
// configuration (geometry.bounds) into the canvas with the aspect kept, so nothing leaves the
// picture. Between states the bodies move on by their velocities (dead reckoning, at most one
// control period ahead) and a jump to a new state is smoothed out over SMOOTH_MS.
'use strict';

const SMOOTH_MS = 60;          // time constant of the correction towards a new state (ms)

class Scene {
  constructor(canvas) {
    this.canvas = canvas;
    this.context = canvas.getContext('2d');
    this.geometry = null;
    this.state = null;           // newest valid state
    this.stateArrived = 0;       // performance.now() of its arrival (ms)
    this.offset = {slider: 0, angle: 0, ball: 0};   // drawn minus newest, at arrival
    this.drawn = null;           // what the last frame drew
    this.stats = {frames: 0, frameTimes: [], latencies: [], statesDrawn: 0,
                  lastDrawnStep: null, lastDrawnEpisode: null};
    this.pendingLatency = null;  // sent_ms of a state not drawn yet
    this.fit = null;
    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    this.resize();
    requestAnimationFrame((time) => this.frame(time));
  }

  resize() {
    const box = this.canvas.parentElement.getBoundingClientRect();
    const ratio = window.devicePixelRatio || 1;
    this.canvas.style.width = box.width + 'px';
    this.canvas.style.height = box.height + 'px';
    this.canvas.width = Math.max(1, Math.round(box.width * ratio));
    this.canvas.height = Math.max(1, Math.round(box.height * ratio));
    this.cssWidth = box.width;
    this.cssHeight = box.height;
    this.drawnKey = null;
    this.fitBounds();
  }

  fitBounds() {
    if (!this.geometry) return;
    const b = this.geometry.bounds;
    const scale = Math.min(this.cssWidth / (b.y_max - b.y_min),
                           this.cssHeight / (b.z_max - b.z_min));
    // Centre the box; px per m is the same on both axes (aspect kept).
    this.fit = {scale: scale,
                x0: (this.cssWidth - (b.y_max - b.y_min) * scale) / 2 - b.y_min * scale,
                y0: (this.cssHeight - (b.z_max - b.z_min) * scale) / 2 + b.z_max * scale};
  }

  // CSS pixel (relative to the canvas) of the world point (y, z) m.
  toPixels(y, z) {
    return [this.fit.x0 + y * this.fit.scale, this.fit.y0 - z * this.fit.scale];
  }

  setGeometry(geometry) {
    this.geometry = geometry;
    this.drawnKey = null;
    this.fitBounds();
  }

  setState(state) {
    const now = performance.now();
    if (this.drawn && this.state && state.episode === this.state.episode && state.step > 0) {
      this.offset = {slider: this.drawn.slider - state.slider, angle: this.drawn.angle - state.angle,
                     ball: this.drawn.ball - state.ball};
    } else {
      this.offset = {slider: 0, angle: 0, ball: 0};   // a new episode: no smoothing across
    }
    this.state = state;
    this.stateArrived = now;
    this.pendingLatency = state.sent_ms;
  }

  // The configuration to draw at time `now` (ms, performance.now()).
  estimate(now) {
    const g = this.geometry, s = this.state;
    const period = g.control_period * 1000;
    const ahead = s.final ? 0 : Math.min(now - this.stateArrived, period) / 1000;
    const decay = Math.exp(-(now - this.stateArrived) / SMOOTH_MS);
    const clamp = (value, limit) => Math.max(-limit, Math.min(limit, value));
    return {
      slider: clamp(s.slider + s.slider_velocity * ahead + this.offset.slider * decay,
                    g.rod_length / 2),
      angle: clamp(s.angle + s.angular_velocity * ahead + this.offset.angle * decay,
                   g.pendulum_limit),
      ball: clamp(s.ball + s.ball_velocity * ahead + this.offset.ball * decay,
                  g.pendulum_length / 2),
    };
  }

  frame(time) {
    requestAnimationFrame((next) => this.frame(next));
    if (!this.geometry || !this.fit) return;
    const stats = this.stats;
    stats.frames += 1;
    stats.frameTimes.push(time);
    if (stats.frameTimes.length > 600) stats.frameTimes.shift();
    const pose = this.state ? this.estimate(time) : {slider: 0, angle: 0, ball: 0};
    // Nothing moves (the sim holds, or between episodes): do not redraw the same picture.
    const key = [pose.slider, pose.angle, pose.ball].map((v) => v.toFixed(5)).join(',')
      + `,${this.canvas.width},${this.canvas.height}`;
    if (key === this.drawnKey && this.pendingLatency === null) return;
    this.drawnKey = key;
    const c = this.context, g = this.geometry, ratio = this.canvas.width / this.cssWidth;
    c.setTransform(ratio, 0, 0, ratio, 0, 0);
    c.fillStyle = g.colors.background;
    c.fillRect(0, 0, this.cssWidth, this.cssHeight);
    this.draw(pose);
    this.drawn = pose;
    stats.draws = (stats.draws || 0) + 1;
    if (this.state && this.pendingLatency !== null) {
      // The state is on screen with this frame: wall time now minus its send time.
      stats.latencies.push(performance.timeOrigin + performance.now() - this.pendingLatency);
      if (stats.latencies.length > 600) stats.latencies.shift();
      stats.statesDrawn += 1;
      stats.lastDrawnStep = this.state.step;
      stats.lastDrawnEpisode = this.state.episode;
      this.pendingLatency = null;
    }
  }

  draw(pose) {
    const c = this.context, g = this.geometry, px = (y, z) => this.toPixels(y, z);
    const scale = this.fit.scale;
    // Target: the level line through the middle of the rod.
    c.strokeStyle = g.colors.target;
    c.lineWidth = 2;
    c.setLineDash([8, 8]);
    c.beginPath();
    const [left, level] = px(g.bounds.y_min, 0), [right] = px(g.bounds.y_max, 0);
    c.moveTo(left, level);
    c.lineTo(right, level);
    c.stroke();
    c.setLineDash([]);
    // Rod: 2 cm longer than the slider's travel at each end.
    const half = g.rod_length / 2 + 0.02, rodHalf = Math.max(2, g.rod_radius * scale);
    const [rodX, rodTop] = px(0, half), [, rodBottom] = px(0, -half);
    c.fillStyle = g.colors.rod;
    c.fillRect(rodX - rodHalf, rodTop, 2 * rodHalf, rodBottom - rodTop);
    c.strokeStyle = '#282828';
    c.beginPath();
    c.moveTo(rodX - 3 * rodHalf, level);
    c.lineTo(rodX + 3 * rodHalf, level);
    c.stroke();
    // Slider: a box centred on the hinge.
    const halfW = Math.max(6, g.slider_width / 2 * scale), halfH = Math.max(4, g.slider_height / 2 * scale);
    const [sx, sz] = px(0, pose.slider);
    c.fillStyle = g.colors.slider;
    c.fillRect(sx - halfW, sz - halfH, 2 * halfW, 2 * halfH);
    // Pendulum: a beam from the hinge to its east end.
    const cos = Math.cos(pose.angle), sin = Math.sin(pose.angle), L = g.pendulum_length;
    const thick = Math.max(6, g.beam_height * scale);
    const [hx, hz] = px(0, pose.slider), [tx, tz] = px(L * cos, pose.slider + L * sin);
    c.strokeStyle = g.colors.pendulum;
    c.lineWidth = thick;
    c.lineCap = 'butt';
    c.beginPath();
    c.moveTo(hx, hz);
    c.lineTo(tx, tz);
    c.stroke();
    // The middle of the beam (the ball's target): a white notch across it.
    const [mx, mz] = px(L / 2 * cos, pose.slider + L / 2 * sin);
    c.strokeStyle = '#ffffff';
    c.lineWidth = 2;
    c.beginPath();
    c.moveTo(mx - sin * thick, mz - cos * thick);
    c.lineTo(mx + sin * thick, mz + cos * thick);
    c.stroke();
    // Ball: on top of the beam (its centre a radius above the beam's upper face).
    const along = L / 2 + pose.ball, above = g.beam_height / 2 + g.ball_radius;
    const [bx, bz] = px(along * cos - above * sin, pose.slider + along * sin + above * cos);
    c.fillStyle = g.colors.ball;
    c.beginPath();
    c.arc(bx, bz, Math.max(5, g.ball_radius * scale), 0, 2 * Math.PI);
    c.fill();
  }
}

// Frame rate and state-to-screen latency over the last `seconds` (for the tests and the console).
function sceneStats(scene, seconds) {
  const times = scene.stats.frameTimes, now = performance.now();
  const recent = times.filter((t) => now - t <= seconds * 1000);
  const lat = scene.stats.latencies.slice().sort((a, b) => a - b);
  const pick = (q) => lat.length ? lat[Math.min(lat.length - 1, Math.floor(q * lat.length))] : null;
  return {fps: recent.length / seconds, draws: scene.stats.draws || 0, latency_median_ms: pick(0.5), latency_p95_ms: pick(0.95),
          latencies: lat.length, frames: scene.stats.frames, statesDrawn: scene.stats.statesDrawn,
          lastDrawnStep: scene.stats.lastDrawnStep, lastDrawnEpisode: scene.stats.lastDrawnEpisode};
}

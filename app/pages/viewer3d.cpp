#include "pages/viewer3d.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "pages/html.h"

namespace dem::viewer3d {
namespace {

static_assert(std::endian::native == std::endian::little, "the viewer's arrays are read as little-endian in the browser");

/// Float32 or Uint32 values as base64 of their bytes (read back with new Float32Array(buffer)).
template <typename T>
std::string pack(const std::vector<T>& values) {
  std::string bytes(values.size() * sizeof(T), '\0');
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  return html::base64(bytes);
}

/// A JSON string literal that is also safe inside <script> (no '<', '>' or '&' as such).
std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\', out += c;
    else if (c == '<' || c == '>' || c == '&' || static_cast<unsigned char>(c) < 0x20) out += fmt::format("\\u{:04x}", static_cast<unsigned char>(c));
    else out += c;
  }
  return out + "\"";
}

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "0"; }

std::string missing(const std::string& why) {
  return "<h2 id=\"view3d\">3D view</h2>\n<p class=\"missing\">3D view not available: " + html::esc(why) + "</p>\n";
}

std::string read_three_js(const Options& options, std::string& path) {
  path = options.three_js;
  if (path.empty()) {
    const char* env = std::getenv("DEMDESIGN_THREE_JS");
    path = env && *env ? env : kDefaultThreeJs;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::stringstream text;
  text << in.rdbuf();
  std::string source = text.str();
  // Inside <script>, "</script" and "<!--" would end or confuse the element; "<\/" is the same in JS.
  for (const char* bad : {"</script", "</SCRIPT", "<!--"})
    for (std::size_t at = source.find(bad); at != std::string::npos; at = source.find(bad, at + 2)) source.insert(at + 1, "\\");
  return source;
}

// The page side: decode the arrays, build the scene, a small orbit/zoom/pan handler (the
// packaged three.js build has no OrbitControls), legends. Everything inside try: on any error
// the viewer box shows the message instead of a canvas.
const char* kScript = R"JS(
(function () {
  var box = document.getElementById('v3d'), msg = document.getElementById('v3d-msg');
  function fail(e) { box.setAttribute('data-state', 'error'); msg.style.display = 'block'; msg.textContent = '3D view not available: ' + (e && e.message ? e.message : e); }
  try {
    if (typeof THREE === 'undefined') throw new Error('three.js did not load');
    var D = JSON.parse(document.getElementById('v3d-data').textContent);
    function f32(b64) { var s = atob(b64), u = new Uint8Array(s.length); for (var i = 0; i < s.length; ++i) u[i] = s.charCodeAt(i); return b64 && u.length ? new Float32Array(u.buffer) : new Float32Array(0); }
    function u32(b64) { var f = f32(b64); return new Uint32Array(f.buffer); }
    var stops = [[0.267,0.005,0.329],[0.283,0.141,0.458],[0.254,0.265,0.530],[0.207,0.372,0.553],[0.164,0.471,0.558],[0.128,0.567,0.551],[0.135,0.659,0.518],[0.267,0.749,0.441],[0.478,0.821,0.318],[0.741,0.873,0.150],[0.993,0.906,0.144]];
    function cmap(t) { if (!(t >= 0)) t = 0; if (t > 1) t = 1; var x = t * (stops.length - 1), i = Math.min(Math.floor(x), stops.length - 2), w = x - i, a = stops[i], b = stops[i + 1]; return [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])]; }
    var gradient = 'linear-gradient(to right,' + stops.map(function (c, i) { return 'rgb(' + c.map(function (v) { return Math.round(255 * v); }).join(',') + ') ' + Math.round(100 * i / (stops.length - 1)) + '%'; }).join(',') + ')';
    // A reversed scale (life: short is hot) runs from the bright end at 0 to the dark end at max.
    function legend(id, title, max, unit, peak, reverse) {
      var el = document.getElementById(id);
      el.innerHTML = '<span class="v3d-lt"></span><span class="v3d-bar"></span><span class="v3d-lt"></span>';
      el.children[0].textContent = title + ' [' + unit + ']: 0';
      el.children[1].style.background = reverse ? gradient.replace('to right', 'to left') : gradient;
      el.children[2].textContent = Number(max).toPrecision(3) + (reverse ? ' and longer' + (peak > 0 ? ' (shortest ' + Number(peak).toPrecision(3) + ')' : '')
                                                                         : (peak > max ? ' and above (peak ' + Number(peak).toPrecision(3) + ')' : ''));
      el.style.display = '';
    }
    var setAttr = function (g, name, a) { if (g.setAttribute) g.setAttribute(name, a); else g.addAttribute(name, a); };

    var width = box.clientWidth, height = box.clientHeight;
    var canvas = document.createElement('canvas'), attributes = { antialias: true, preserveDrawingBuffer: true };
    var gl = canvas.getContext('webgl', attributes) || canvas.getContext('experimental-webgl', attributes);
    if (!gl) throw new Error('this browser offers no WebGL (hardware acceleration off?)');
    var renderer = new THREE.WebGLRenderer({ canvas: canvas, context: gl });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setSize(width, height);
    renderer.setClearColor(0xeceff4, 1);
    box.appendChild(renderer.domElement);
    var scene = new THREE.Scene();
    var camera = new THREE.PerspectiveCamera(40, width / height, 1e-4, 1e4);
    scene.add(camera);
    scene.add(new THREE.AmbientLight(0xffffff, 0.55));
    var sun = new THREE.DirectionalLight(0xffffff, 0.6);
    sun.position.set(0.3, 0.6, 1);
    camera.add(sun);

    // Walls: one colour per triangle (non-indexed geometry).
    var walls = [], lo = new THREE.Vector3(Infinity, Infinity, Infinity), hi = lo.clone().negate();
    D.meshes.forEach(function (m) {
      var p = f32(m.p), t = u32(m.t), n = t.length / 3, pos = new Float32Array(9 * n);
      for (var k = 0; k < 3 * n; ++k) for (var c = 0; c < 3; ++c) pos[3 * k + c] = p[3 * t[k] + c];
      for (var v = 0; v < p.length; v += 3) { lo.min(new THREE.Vector3(p[v], p[v + 1], p[v + 2])); hi.max(new THREE.Vector3(p[v], p[v + 1], p[v + 2])); }
      var g = new THREE.BufferGeometry();
      setAttr(g, 'position', new THREE.BufferAttribute(pos, 3));
      setAttr(g, 'color', new THREE.BufferAttribute(new Float32Array(9 * n), 3));
      g.computeVertexNormals();
      var mat = new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors !== undefined ? THREE.VertexColors : true, side: THREE.DoubleSide, transparent: true, opacity: 0.6, depthWrite: false });
      var mesh = new THREE.Mesh(g, mat);
      scene.add(mesh);
      var fields = {};
      ['shear', 'impact', 'pressure', 'life'].forEach(function (k) { fields[k] = m[k] ? f32(m[k]) : null; });
      walls.push({ mesh: mesh, n: n, fields: fields });
    });
    function colourWalls(field) {
      var f = D.fields[field];
      walls.forEach(function (w) {
        var col = w.mesh.geometry.attributes.color, values = f ? w.fields[field] : null;
        for (var k = 0; k < w.n; ++k) {
          var v = values ? values[k] : NaN, s = f && f.max > 0 ? v / f.max : (f && f.reverse ? 1 : 0);
          var rgb = f && isFinite(v) ? cmap(f.reverse ? 1 - s : s) : [0.72, 0.74, 0.78];
          for (var c = 0; c < 3; ++c) for (var j = 0; j < 3; ++j) col.array[9 * k + 3 * c + j] = rgb[j];
        }
        col.needsUpdate = true;
      });
      if (f) legend('v3d-wall-legend', f.label, f.max, f.unit, f.peak, f.reverse); else document.getElementById('v3d-wall-legend').style.display = 'none';
    }

    // Particles: sphere sprites sized by radius in perspective, shaded as spheres.
    var P = D.particles, points = null;
    if (P.n > 0) {
      var pp = f32(P.p), pr = f32(P.r), ps = f32(P.s), colour = new Float32Array(3 * P.n);
      for (var i = 0; i < P.n; ++i) {
        var rgb = cmap(D.speedMax > 0 ? ps[i] / D.speedMax : 0);
        colour[3 * i] = rgb[0], colour[3 * i + 1] = rgb[1], colour[3 * i + 2] = rgb[2];
        lo.min(new THREE.Vector3(pp[3 * i] - pr[i], pp[3 * i + 1] - pr[i], pp[3 * i + 2] - pr[i]));
        hi.max(new THREE.Vector3(pp[3 * i] + pr[i], pp[3 * i + 1] + pr[i], pp[3 * i + 2] + pr[i]));
      }
      var pg = new THREE.BufferGeometry();
      setAttr(pg, 'position', new THREE.BufferAttribute(pp, 3));
      setAttr(pg, 'radius', new THREE.BufferAttribute(pr, 1));
      setAttr(pg, 'pcolour', new THREE.BufferAttribute(colour, 3));
      var sprite = new THREE.ShaderMaterial({
        uniforms: { scale: { value: 1 } },
        vertexShader: 'attribute float radius; attribute vec3 pcolour; uniform float scale; varying vec3 vColour;\n' +
          'void main() { vColour = pcolour; vec4 mv = modelViewMatrix * vec4(position, 1.0); gl_Position = projectionMatrix * mv;\n' +
          '  gl_PointSize = max(2.0, scale * radius / -mv.z); }',
        fragmentShader: 'varying vec3 vColour;\n' +
          'void main() { vec2 c = 2.0 * gl_PointCoord - 1.0; float r2 = dot(c, c); if (r2 > 1.0) discard;\n' +
          '  vec3 n = vec3(c.x, -c.y, sqrt(1.0 - r2)); float l = 0.45 + 0.55 * max(0.0, dot(n, normalize(vec3(0.35, 0.5, 0.8))));\n' +
          '  gl_FragColor = vec4(vColour * l, 1.0); }'
      });
      points = new THREE.Points(pg, sprite);
      scene.add(points);
      legend('v3d-speed-legend', 'particle speed', D.speedMax, 'm/s');
    }
    if (!isFinite(lo.x)) { lo.set(-0.5, -0.5, -0.5); hi.set(0.5, 0.5, 0.5); }

    function draw() {
      if (points) points.material.uniforms.scale.value = box.clientHeight * renderer.getPixelRatio() / Math.tan(camera.fov * Math.PI / 360);
      renderer.render(scene, camera);
    }

    // Orbit about a target around the up axis (against gravity), zoom with the wheel, pan with
    // the right button or shift + left button.
    var up = new THREE.Vector3(D.up[0], D.up[1], D.up[2]).normalize();
    camera.up.copy(up);
    var toY = new THREE.Quaternion().setFromUnitVectors(up, new THREE.Vector3(0, 1, 0)), fromY = toY.clone().conjugate();
    var centre = lo.clone().add(hi).multiplyScalar(0.5), size = Math.max(hi.clone().sub(lo).length(), 1e-3);
    var target = new THREE.Vector3(), orbit = new THREE.Spherical();
    function place() {
      orbit.makeSafe();
      camera.position.copy(target).add(new THREE.Vector3().setFromSpherical(orbit).applyQuaternion(fromY));
      camera.near = orbit.radius / 1000, camera.far = orbit.radius + 10 * size;
      camera.lookAt(target);
      camera.updateProjectionMatrix();
      draw();
    }
    function reset() { target.copy(centre); orbit.set(0.9 * size / (2 * Math.tan(camera.fov * Math.PI / 360)), 1.0, 0.7); place(); }
    var drag = null;
    var el = renderer.domElement;
    el.addEventListener('contextmenu', function (e) { e.preventDefault(); });
    el.addEventListener('mousedown', function (e) { drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey }; e.preventDefault(); });
    window.addEventListener('mouseup', function () { drag = null; });
    window.addEventListener('mousemove', function (e) {
      if (!drag) return;
      var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX, drag.y = e.clientY;
      if (drag.pan) {
        var k = 2 * orbit.radius * Math.tan(camera.fov * Math.PI / 360) / box.clientHeight;
        var right = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 0), upv = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 1);
        target.add(right.multiplyScalar(-dx * k)).add(upv.multiplyScalar(dy * k));
      } else {
        orbit.theta -= 2 * Math.PI * dx / box.clientHeight;
        orbit.phi -= 2 * Math.PI * dy / box.clientHeight;
      }
      place();
    });
    el.addEventListener('wheel', function (e) { e.preventDefault(); orbit.radius *= Math.exp(0.001 * Math.max(-300, Math.min(300, e.deltaY))); place(); }, { passive: false });
    window.addEventListener('resize', function () {
      renderer.setSize(box.clientWidth, box.clientHeight);
      camera.aspect = box.clientWidth / box.clientHeight;
      place();
    });
    document.getElementById('v3d-reset').addEventListener('click', reset);
    var select = document.getElementById('v3d-field');
    select.addEventListener('change', function () { colourWalls(select.value); draw(); });
    colourWalls(select.value);
    reset();
    box.setAttribute('data-state', 'drawn');
  } catch (e) { fail(e); }
})();
)JS";

const char* kStyle = R"(<style>
#v3d{position:relative;width:100%;height:560px;background:#eceff4;border:1px solid #ccd;cursor:grab}
#v3d canvas{display:block}#v3d-msg{position:absolute;top:0;left:0;right:0;padding:10px;color:#555}
.v3d-tools{margin:6px 0;display:flex;flex-wrap:wrap;gap:14px;align-items:center;font-size:13px}
.v3d-legend{display:inline-flex;align-items:center;gap:6px}.v3d-bar{display:inline-block;width:160px;height:12px;border:1px solid #999}
</style>
)";

/// One colour field of the walls: its key (the select box's value and the meshes' entry), how it
/// is labelled, and every triangle's finite value for its colour scale.
struct WallField {
  const char* name;
  const char* label;   ///< the legend's title
  const char* option;  ///< the select box's text
  const char* unit;    ///< as JSON text
  bool reverse = false;  ///< short is hot: life, whose scale runs from 0 (bright) to its top (dark)
  bool present = false;  ///< some triangle has a value
  std::vector<double> all;
};

/// The walls' fields in the select box's order.
struct WallFields {
  WallField shear{"shear", "shear work rate", "shear work rate (wear)", "W/m\\u00b2", false, false, {}};
  WallField impact{"impact", "impact energy rate", "impact energy rate", "W/m\\u00b2", false, false, {}};
  WallField pressure{"pressure", "mean pressure", "mean pressure [kPa]", "kPa", false, false, {}};
  WallField life{"life", "liner life", "liner life [months], short is yellow", "months", true, false, {}};
  std::vector<WallField*> all() { return {&shear, &impact, &pressure, &life}; }
};

/// `scale` x a record's total per area and second over `seconds` [s], per triangle; NaN on a
/// triangle of no area or without a value.
std::vector<double> per_area(const TriangleSurface& surface, const std::vector<double>& total, double seconds, double scale) {
  std::vector<double> out(surface.size(), std::nan(""));
  for (std::size_t t = 0; t < surface.size() && t < total.size(); ++t)
    if (surface.areas[t] > 0 && std::isfinite(total[t])) out[t] = scale * total[t] / (seconds * surface.areas[t]);
  return out;
}

/// A mesh's entry of `field` (",\"name\":\"base64\""), its finite values kept for the scale. An
/// infinite value (a liner that does not wear) is sent as the largest float: the far end of the scale.
std::string field_entry(WallField& field, const std::vector<double>& values) {
  std::vector<float> out;
  for (const double v : values) {
    out.push_back(std::isinf(v) ? std::numeric_limits<float>::max() : float(v));
    if (!std::isnan(v)) field.present = true;
    if (std::isfinite(v)) field.all.push_back(v);
  }
  return fmt::format(",\"{}\":\"{}\"", field.name, pack(out));
}

/// Mesh m in its pose at the end, with its wall fields over the records' interval `seconds` [s]:
/// shear work and impact energy rates [W/m^2], mean pressure [kPa], and the liner life [months]
/// the caller gave.
std::string mesh_entry(const Model& model, const State& state, std::size_t m, double seconds, const Options& options, WallFields& fields) {
  const TriangleSurface& surface = *model.meshes[m].surface;
  const Pose pose = model.meshes[m].motion.pose(state.time);
  std::vector<float> position;
  for (const auto& v : surface.vertices) {
    const Eigen::Vector3d w = pose.rotation * Eigen::Vector3d(v[0], v[1], v[2]) + pose.translation;
    position.insert(position.end(), {float(w.x()), float(w.y()), float(w.z())});
  }
  std::vector<std::uint32_t> triangles;
  for (const auto& t : surface.triangles) triangles.insert(triangles.end(), {std::uint32_t(t[0]), std::uint32_t(t[1]), std::uint32_t(t[2])});
  std::string entry = fmt::format("{{\"name\":{},\"p\":\"{}\",\"t\":\"{}\"", json_string(model.meshes[m].name), pack(position), pack(triangles));
  if (m < state.records.size() && seconds > 0) {
    const TriangleRecords& rec = state.records[m];
    entry += field_entry(fields.shear, per_area(surface, rec.shear_work, seconds, 1.0));
    entry += field_entry(fields.impact, per_area(surface, rec.impact_energy, seconds, 1.0));
    entry += field_entry(fields.pressure, per_area(surface, rec.normal_impulse, seconds, 1e-3));  // Pa to kPa
  }
  if (m < options.life_months.size()) entry += field_entry(fields.life, options.life_months[m]);
  return entry + "}";
}

/// A field's colour scale. Rates and pressure: 0 to the 99th percentile over the triangles, as in
/// the wear maps (app/pages/flow_images.cpp): one hot triangle does not turn every other one
/// dark; the peak is in the legend. Life, reversed: 0 to the median over the worn triangles,
/// longer lives at the dark end, the shortest in the legend (rejected: 1/life, a wear rate the
/// other fields already show).
std::string field_scale(WallField& field) {
  std::vector<double>& all = field.all;
  std::sort(all.begin(), all.end());
  const auto rank = [&all](double q) { return all.empty() ? 0.0 : all[static_cast<std::size_t>(q * double(all.size() - 1))]; };
  const double top = field.reverse ? rank(0.5) : rank(0.99);
  const double peak = all.empty() ? 0.0 : field.reverse ? all.front() : all.back();
  return fmt::format("\"{}\":{{\"label\":\"{}\",\"unit\":\"{}\",\"max\":{},\"peak\":{}{}}}", field.name, field.label, field.unit, json_number(top),
                     json_number(peak), field.reverse ? ",\"reverse\":true" : "");
}

/// The particles of the final state, evenly subsampled above the limit, as JSON; their fastest speed [m/s].
std::string particles_entry(const State& state, const Options& options, double& speed_max) {
  const std::size_t total = state.owned(), limit = std::max<std::size_t>(options.max_particles, 1);
  const std::size_t shown = std::min(total, limit);
  std::vector<float> position, radius, speed;
  speed_max = 0;
  for (std::size_t k = 0; k < shown; ++k) {
    const std::size_t p = total > limit ? k * total / limit : k;
    const double s = std::sqrt(state.vx[p] * state.vx[p] + state.vy[p] * state.vy[p] + state.vz[p] * state.vz[p]);
    position.insert(position.end(), {float(state.x[p]), float(state.y[p]), float(state.z[p])});
    radius.push_back(float(state.radius[p]));
    speed.push_back(float(s));
    if (std::isfinite(s)) speed_max = std::max(speed_max, s);
  }
  return fmt::format("{{\"n\":{},\"p\":\"{}\",\"r\":\"{}\",\"s\":\"{}\"}}", shown, pack(position), pack(radius), pack(speed));
}

/// The view's data: up, the meshes with their fields, the fields' scales, the particles.
std::string view_data(const Model& model, const State& state, double records_from, const Options& options, WallFields& fields) {
  const double seconds = state.time - records_from;  // [s] the records' interval
  std::string meshes;
  for (std::size_t m = 0; m < model.meshes.size(); ++m) meshes += (meshes.empty() ? "" : ",") + mesh_entry(model, state, m, seconds, options, fields);
  std::string scales;
  for (WallField* f : fields.all())
    if (f->present) scales += (scales.empty() ? "" : ",") + field_scale(*f);
  double speed_max = 0;
  const std::string particles = particles_entry(state, options, speed_max);
  Eigen::Vector3d up = -Eigen::Vector3d(model.gravity[0], model.gravity[1], model.gravity[2]);
  if (!(up.norm() > 0)) up = Eigen::Vector3d::UnitZ();
  up.normalize();
  return fmt::format("{{\"up\":[{},{},{}],\"meshes\":[{}],\"fields\":{{{}}},\"speedMax\":{},\"particles\":{}}}", json_number(up.x()),
                     json_number(up.y()), json_number(up.z()), meshes, scales, json_number(speed_max), particles);
}

/// What the view shows, above it.
std::string intro(const Model& model, const State& state, double records_from, const Options& options, const WallFields& fields) {
  const std::size_t total = state.owned(), limit = std::max<std::size_t>(options.max_particles, 1);
  std::string h = fmt::format("<p>The walls in their pose at t = {} s and the {} particles of the final state, coloured by speed. "
                              "Drag to orbit, right-drag or shift-drag to pan, the wheel zooms.",
                              html::num(state.time, 4), total);
  if (total > limit)
    h += fmt::format(" <b>Subsampled:</b> {} of the {} particles are shown (evenly over the particle slots, about 1 in {:.3g}), "
                     "to keep this file small.", limit, total, double(total) / double(limit));
  if (fields.shear.present)
    h += fmt::format(" Wall fields are averaged over t = {} to {} s, per triangle area (mean pressure: normal impulse per area and "
                     "time, in kPa); the colour scale runs from 0 to the 99th percentile over the triangles (the peak is beside it).",
                     html::num(records_from, 3), html::num(state.time, 4));
  else if (!model.meshes.empty())
    h += " No wall records yet (recording starts at " + html::num(records_from, 3) + " s): the walls are plain.";
  if (fields.life.present)
    h += " Liner life: months until the liner is worn through at each triangle, from its sliding and impact wear rates at the "
         "report&#39;s operating hours; short lives are yellow, the scale runs from 0 to the median life over the worn triangles "
         "(longer lives are dark, the shortest is beside it), grey where a mesh has no liner.";
  return h + "</p>\n";
}

/// The tools above the canvas: the select box of the wall fields, the reset button, the legends.
std::string tools(const WallFields& fields) {
  std::string h = "<div class=\"v3d-tools\"><label>Walls coloured by <select id=\"v3d-field\">";
  const std::vector<const WallField*> all = {&fields.shear, &fields.impact, &fields.pressure, &fields.life};
  bool first = true;
  for (const WallField* f : all) {
    if (!f->present) continue;
    h += fmt::format("<option value=\"{}\"{}>{}</option>", f->name, first ? " selected" : "", html::esc(f->option));
    first = false;
  }
  return h + "<option value=\"plain\">plain</option></select></label><button type=\"button\" id=\"v3d-reset\">Reset view</button>"
             "<span class=\"v3d-legend\" id=\"v3d-wall-legend\" style=\"display:none\"></span>"
             "<span class=\"v3d-legend\" id=\"v3d-speed-legend\" style=\"display:none\"></span></div>\n";
}

std::string build(const Model& model, const State& state, double records_from, const Options& options) {
  std::string three_path;
  const std::string three = read_three_js(options, three_path);
  if (three.empty())
    return missing("three.js not found at " + three_path + " (install the Debian package libjs-three to get the interactive view)");
  WallFields fields;
  const std::string data = view_data(model, state, records_from, options, fields);
  std::string h = "<h2 id=\"view3d\">3D view</h2>\n";
  h += intro(model, state, records_from, options, fields);
  h += std::string(kStyle) + tools(fields);
  h += "<div id=\"v3d\" data-state=\"loading\"><div id=\"v3d-msg\" style=\"display:none\"></div>"
       "<noscript>The 3D view needs JavaScript and WebGL.</noscript></div>\n";
  h += "<script>/* three.js (MIT licence), inlined from " + html::esc(three_path) + " */\n" + three + "\n</script>\n";
  h += "<script type=\"application/json\" id=\"v3d-data\">" + data + "</script>\n";
  h += "<script>" + std::string(kScript) + "</script>\n";
  return h;
}

}  // namespace

std::string section(const Model& model, const State& state, double records_from, const Options& options) {
  try {
    return build(model, state, records_from, options);
  } catch (const std::exception& e) {
    return missing(e.what());
  } catch (...) {
    return missing("unknown error while preparing the view");
  }
}

}  // namespace dem::viewer3d

// GLSL 3.30 programs: sphere impostors and lit triangles, sharing one lighting function.
#pragma once

namespace dem::render::shaders {

// Lighting in eye space: a key light from the upper left behind the camera, a head light so that
// nothing facing the viewer goes black, ambient, and a Blinn-Phong highlight. A surface facing the
// viewer gets 0.25 + 0.5 * 0.81 + 0.35 = 1.0 times its colour, so colour-map colours read true.
inline constexpr const char* lighting = R"(
vec3 shade(vec3 base, vec3 n, vec3 to_eye) {
  const vec3 key = vec3(-0.3254, 0.4881, 0.8135);  // normalize(-0.4, 0.6, 1)
  float diffuse = max(dot(n, key), 0.0);
  float head = max(dot(n, to_eye), 0.0);
  float highlight = pow(max(dot(n, normalize(key + to_eye)), 0.0), 48.0);
  return base * (0.25 + 0.5 * diffuse + 0.35 * head) + 0.2 * highlight;
}
)";

// A sphere is a square facing the eye that just covers its silhouette: for perspective, the
// tangent cone's section through the centre has radius r d / sqrt(d^2 - r^2).
inline constexpr const char* sphere_vertex = R"(#version 330 core
layout(location = 0) in vec2 corner;  // (+-1, +-1)
layout(location = 1) in vec4 sphere;  // centre relative to the target, radius
layout(location = 2) in vec4 colour;
uniform mat4 view, projection;
uniform bool orthographic;
out vec3 quad_position;
flat out vec3 centre;
flat out float radius;
flat out vec3 base_colour;
void main() {
  centre = (view * vec4(sphere.xyz, 1.0)).xyz;
  radius = sphere.w;
  base_colour = colour.rgb;
  vec3 right = vec3(1.0, 0.0, 0.0), up = vec3(0.0, 1.0, 0.0);
  float half_size = radius;
  if (!orthographic) {
    float d = length(centre);
    if (d <= radius * 1.0001) {  // the eye is inside: draw nothing
      gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
      quad_position = vec3(0.0);
      return;
    }
    vec3 axis = centre / d;
    right = normalize(cross(axis, abs(axis.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    up = cross(right, axis);
    half_size = radius * d / sqrt(d * d - radius * radius);
  }
  quad_position = centre + half_size * (corner.x * right + corner.y * up);
  gl_Position = projection * vec4(quad_position, 1.0);
}
)";

// Ray-sphere intersection per pixel, exact depth, and coverage from the distance to the rim in
// pixels (alpha-to-coverage turns it into multisample coverage, so silhouettes are smooth).
inline constexpr const char* sphere_fragment = R"(
in vec3 quad_position;
flat in vec3 centre;
flat in float radius;
flat in vec3 base_colour;
uniform mat4 projection;
uniform bool orthographic;
uniform float min_coverage;
out vec4 fragment;
void main() {
  vec3 origin = orthographic ? vec3(quad_position.xy, 0.0) : vec3(0.0);
  vec3 direction = orthographic ? vec3(0.0, 0.0, -1.0) : normalize(quad_position);
  vec3 to_centre = centre - origin;
  float along = dot(direction, to_centre);
  // Distance of the ray from the centre; from the perpendicular vector, not d^2 - b^2, which
  // cancels catastrophically for a small sphere far away.
  float miss = length(to_centre - along * direction);
  float coverage = clamp((radius - miss) / max(fwidth(miss), 1e-30) + 0.5, 0.0, 1.0);
  if (coverage < min_coverage) discard;
  float inside = sqrt(max(radius * radius - miss * miss, 0.0));
  vec3 hit = origin + (along - inside) * direction;
  vec3 normal = (hit - centre) / radius;
  vec4 clip = projection * vec4(hit, 1.0);
  gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;
  fragment = vec4(shade(base_colour, normalize(normal), -direction), coverage);
}
)";

inline constexpr const char* mesh_vertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 colour;
uniform mat4 view, projection;
out vec3 eye_position;
out vec3 eye_normal;
flat out vec4 face_colour;
void main() {
  eye_position = (view * vec4(position, 1.0)).xyz;
  eye_normal = mat3(view) * normal;  // the view is a rotation plus a shift
  face_colour = colour;
  gl_Position = projection * vec4(eye_position, 1.0);
}
)";

// Both sides of a wall are lit: the normal is flipped towards the viewer.
inline constexpr const char* mesh_fragment = R"(
in vec3 eye_position;
in vec3 eye_normal;
flat in vec4 face_colour;
uniform bool orthographic;
out vec4 fragment;
void main() {
  vec3 to_eye = orthographic ? vec3(0.0, 0.0, 1.0) : normalize(-eye_position);
  vec3 n = normalize(eye_normal);
  if (dot(n, to_eye) < 0.0) n = -n;
  fragment = vec4(shade(face_colour.rgb, n, to_eye), face_colour.a);
}
)";

}  // namespace dem::render::shaders

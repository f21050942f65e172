#version 450
// Mesh renderer, fragment stage.
//   shade:  Phong with a headlight (light at the eye) + ambient, on a light grey
//   normal: the interpolated vertex normal mapped to RGB (n * 0.5 + 0.5)
//   age:    warm (red, age 0) to cold (blue, oldest) colormap of the normalised age, lightly shaded
//   rgb:    the vertex colour, lightly shaded (grey where a vertex has none)
// No culling: a back face (seen against its winding) is drawn at half brightness.
#extension GL_GOOGLE_include_directive : require
#include "mesh_render.h"

layout(location = 0) in vec3 worldPos;
layout(location = 1) in vec3 worldNormal;
layout(location = 2) in float age;
layout(location = 3) in vec4 vertexColor;

layout(location = 0) out vec4 outColor;

const float BACK_FACE_FACTOR = 0.5;

// Hue ramp red (t = 0) -> yellow -> green -> cyan -> blue (t = 1).
vec3 warmToCold(float t) {
    t = clamp(t, 0.0, 1.0);
    float h = t * 4.0;  // 0..4 over the four segments
    vec3 c;
    if (h < 1.0) c = vec3(1.0, h, 0.0);
    else if (h < 2.0) c = vec3(2.0 - h, 1.0, 0.0);
    else if (h < 3.0) c = vec3(0.0, 1.0, h - 2.0);
    else c = vec3(0.0, 4.0 - h, 1.0);
    return c;
}

void main() {
    // A zero or missing normal falls back to the face normal from screen-space derivatives.
    vec3 n = worldNormal;
    if (dot(n, n) < 1e-12) n = cross(dFdx(worldPos), dFdy(worldPos));
    n = dot(n, n) > 1e-24 ? normalize(n) : vec3(0.0, 0.0, 1.0);

    vec3 v = normalize(pc.eye.xyz - worldPos);
    vec3 facing = gl_FrontFacing ? n : -n;           // the side of the surface the camera sees
    float lambert = abs(dot(n, v));                  // headlight: L = V
    float specular = pow(max(dot(reflect(-v, facing), v), 0.0), 32.0);

    vec3 color;
    if (pc.colorMode == RENDER_COLOR_NORMAL) {
        color = n * 0.5 + 0.5;
    } else if (pc.colorMode == RENDER_COLOR_RGB) {
        vec3 albedo = vertexColor.a > 0.0 ? vertexColor.rgb : vec3(0.5);
        color = albedo * (0.55 + 0.45 * lambert);
    } else if (pc.colorMode == RENDER_COLOR_AGE) {
        color = warmToCold(age) * (0.45 + 0.55 * lambert);
    } else {
        vec3 base = vec3(0.8);
        color = base * (0.18 + 0.82 * lambert) + vec3(0.25) * specular;
    }
    if (!gl_FrontFacing) color *= BACK_FACE_FACTOR;
    outColor = vec4(clamp(color, 0.0, 1.0), 1.0);
}

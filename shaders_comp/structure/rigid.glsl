// Rigid transforms as the shaders get them: the 3 rows of [R | t] (x' = row.x*x + row.y*y + row.z*z + row.w),
// written out so that the order of the operations (and so the rounding) is the one the CPU reference
// (src/core/camera.h, RigidRows; src/cpu) uses. Shared by the volume's stages (frame.glsl) and tracking's.
#ifndef VKMESH_RIGID_GLSL
#define VKMESH_RIGID_GLSL

// x' = R x + t
vec3 transformPoint(vec4 rows[3], vec3 p) {
    precise vec3 q;
    q.x = rows[0].x * p.x + rows[0].y * p.y + rows[0].z * p.z + rows[0].w;
    q.y = rows[1].x * p.x + rows[1].y * p.y + rows[1].z * p.z + rows[1].w;
    q.z = rows[2].x * p.x + rows[2].y * p.y + rows[2].z * p.z + rows[2].w;
    return q;
}

// R v (a direction: no translation)
vec3 rotateVector(vec4 rows[3], vec3 v) {
    precise vec3 q;
    q.x = rows[0].x * v.x + rows[0].y * v.y + rows[0].z * v.z;
    q.y = rows[1].x * v.x + rows[1].y * v.y + rows[1].z * v.z;
    q.z = rows[2].x * v.x + rows[2].y * v.y + rows[2].z * v.z;
    return q;
}

// R^T v (the inverse rotation)
vec3 rotateVectorTransposed(vec4 rows[3], vec3 v) {
    precise vec3 q;
    q.x = rows[0].x * v.x + rows[1].x * v.y + rows[2].x * v.z;
    q.y = rows[0].y * v.x + rows[1].y * v.y + rows[2].y * v.z;
    q.z = rows[0].z * v.x + rows[1].z * v.y + rows[2].z * v.z;
    return q;
}
#endif

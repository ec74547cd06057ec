// The G-buffer of the prepass, bound at group 3 for every technique shader
// (`frame::GBUFFER_GROUP`).

// xyz world position, w object index + 1 where geometry was drawn (0: background)
@group(3) @binding(0) var gbuffer_position: texture_2d<f32>;
// xyz geometric normal facing the camera, w 1 if the surface receives shadows
@group(3) @binding(1) var gbuffer_normal: texture_2d<f32>;
// the convex part drawn (`part_id` in common.wgsl), 0: none
@group(3) @binding(2) var gbuffer_part: texture_2d<u32>;

// Procedural textures of [004]: stripes, checker, and
// Perlin's improved noise (fade 6t^5 − 15t^4 + 10t^3) summed in octaves
// weighted 1/o, its absolute value (turbulence) and a sine of it (marble).

fn hash3(p: vec3i) -> u32 {
    var h = (u32(p.x) * 73856093u) ^ (u32(p.y) * 19349663u) ^ (u32(p.z) * 83492791u);
    h = (h ^ (h >> 13u)) * 1274126177u;
    return h ^ (h >> 16u);
}

// Gradient from Perlin's 12 cube-edge directions.
fn grad(h: u32, p: vec3f) -> f32 {
    let g = h & 15u;
    let u = select(p.y, p.x, g < 8u);
    let v = select(select(p.z, p.x, g == 12u || g == 14u), p.y, g < 4u);
    return select(-u, u, (g & 1u) == 0u) + select(-v, v, (g & 2u) == 0u);
}

fn fade(t: vec3f) -> vec3f {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

fn perlin(p: vec3f) -> f32 {
    let i = vec3i(floor(p));
    let f = fract(p);
    let u = fade(f);
    let n000 = grad(hash3(i), f);
    let n100 = grad(hash3(i + vec3i(1, 0, 0)), f - vec3f(1.0, 0.0, 0.0));
    let n010 = grad(hash3(i + vec3i(0, 1, 0)), f - vec3f(0.0, 1.0, 0.0));
    let n110 = grad(hash3(i + vec3i(1, 1, 0)), f - vec3f(1.0, 1.0, 0.0));
    let n001 = grad(hash3(i + vec3i(0, 0, 1)), f - vec3f(0.0, 0.0, 1.0));
    let n101 = grad(hash3(i + vec3i(1, 0, 1)), f - vec3f(1.0, 0.0, 1.0));
    let n011 = grad(hash3(i + vec3i(0, 1, 1)), f - vec3f(0.0, 1.0, 1.0));
    let n111 = grad(hash3(i + vec3i(1, 1, 1)), f - vec3f(1.0, 1.0, 1.0));
    let x00 = mix(n000, n100, u.x);
    let x10 = mix(n010, n110, u.x);
    let x01 = mix(n001, n101, u.x);
    let x11 = mix(n011, n111, u.x);
    return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

// Σ_{o=1..N} |noise(2^(o−1) p)| / o.
fn turbulence(p: vec3f, octaves: u32) -> f32 {
    var sum = 0.0;
    var freq = 1.0;
    for (var o = 1u; o <= octaves; o++) {
        sum += abs(perlin(p * freq)) / f32(o);
        freq *= 2.0;
    }
    return sum;
}

// kind: 1 stripes, 2 checker, 3 marble, 4 turbulence. Returns the blend
// factor between colour a (0) and colour b (1).
fn procedural_factor(kind: u32, p: vec3f, scale: f32, octaves: u32) -> f32 {
    let q = p * scale;
    switch kind {
        case 1u: {
            return step(0.5, fract(q.x));
        }
        case 2u: {
            let c = vec3i(floor(q + 1e-4));
            return f32((c.x + c.y + c.z) & 1);
        }
        case 3u: {
            return 0.5 + 0.5 * sin(q.x * 3.14159 + 4.0 * turbulence(q, octaves));
        }
        default: {
            return clamp(turbulence(q, octaves), 0.0, 1.0);
        }
    }
}

// Texture lookups: a hit's texture coordinates and the bilinear, sRGB-decoded colour there.
// Mirrors: src/integrator/texture.rs (the equations: docs/textures.md).

// The texture coordinates of `hit` on `prim`, whose outward normal there is `outward`.
fn texture_coordinates(prim: GpuPrimitive, hit: Hit, outward: vec3<f32>) -> vec2<f32> {
    switch prim.kind {
        case PRIM_TRIANGLE: {
            if (prim.normals >= arrayLength(&texcoords)) {
                return vec2<f32>(0.0);
            }
            let t = texcoords[prim.normals].uv;
            let b0 = 1.0 - hit.b1 - hit.b2;
            return b0 * vec2<f32>(t[0], t[1]) + hit.b1 * vec2<f32>(t[2], t[3])
                + hit.b2 * vec2<f32>(t[4], t[5]);
        }
        case PRIM_QUAD: {
            return vec2<f32>(hit.b1, 1.0 - hit.b2);
        }
        case PRIM_SPHERE: {
            return sphere_coordinates(outward);
        }
        default: {
            return vec2<f32>(0.0);
        }
    }
}

fn sphere_coordinates(n: vec3<f32>) -> vec2<f32> {
    let longitude = atan2(-n.z, n.x);
    let u = longitude / (2.0 * PI);
    return vec2<f32>(u - floor(u), acos(clamp(n.y, -1.0, 1.0)) / PI);
}

fn srgb_to_linear(c: f32) -> f32 {
    if (c <= 0.04045) {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn decode_texel(texel: u32) -> vec3<f32> {
    let channel = vec3<f32>(vec3<u32>(texel, texel >> 8u, texel >> 16u) & vec3<u32>(0xffu)) / 255.0;
    return vec3<f32>(srgb_to_linear(channel.x), srgb_to_linear(channel.y), srgb_to_linear(channel.z));
}

fn wrap_coordinate(x: f32, mode: u32) -> f32 {
    switch mode {
        case WRAP_CLAMP: {
            return clamp(x, 0.0, 1.0);
        }
        case WRAP_MIRROR: {
            return x - 2.0 * floor(0.5 * x);
        }
        default: {
            return x - floor(x);
        }
    }
}

// Euclidean remainder of i by n > 0.
fn rem_euclid(i: i32, n: i32) -> i32 {
    let r = i % n;
    return select(r, r + n, r < 0);
}

fn wrap_index(i: i32, size: i32, mode: u32) -> u32 {
    switch mode {
        case WRAP_CLAMP: {
            return u32(clamp(i, 0, size - 1));
        }
        case WRAP_MIRROR: {
            let m = rem_euclid(i, 2 * size);
            return u32(select(m, 2 * size - 1 - m, m >= size));
        }
        default: {
            return u32(rem_euclid(i, size));
        }
    }
}

fn texel_at(texture: GpuTexture, column: u32, row: u32) -> vec3<f32> {
    let index = texture.offset + row * texture.width + column;
    if (index >= arrayLength(&texels)) {
        return vec3<f32>(0.0);
    }
    return decode_texel(texels[index]);
}

fn texture_lookup(texture: GpuTexture, uv: vec2<f32>) -> vec3<f32> {
    let size = vec2<i32>(i32(texture.width), i32(texture.height));
    let wrap_u = texture.wrap & 0xffu;
    let wrap_v = texture.wrap >> 8u;
    let x = wrap_coordinate(uv.x, wrap_u) * f32(size.x) - 0.5;
    let y = wrap_coordinate(uv.y, wrap_v) * f32(size.y) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let c0 = wrap_index(i32(x0), size.x, wrap_u);
    let c1 = wrap_index(i32(x0) + 1, size.x, wrap_u);
    let r0 = wrap_index(i32(y0), size.y, wrap_v);
    let r1 = wrap_index(i32(y0) + 1, size.y, wrap_v);
    let top = texel_at(texture, c0, r0) * (1.0 - fx) + texel_at(texture, c1, r0) * fx;
    let bottom = texel_at(texture, c0, r1) * (1.0 - fx) + texel_at(texture, c1, r1) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

/* Blender's hash functions, as Cycles 3.4 computes them (intern/cycles/util/hash.h,
 * read from the Cycles kernel sources that Blender 3.4.1 ships in
 * scripts/addons/cycles/source/util/hash.h).
 *
 * All integer arithmetic is GLSL `uint`, which wraps modulo 2^32 like C's uint32_t,
 * so the Jenkins lookup3 hashes are bit-exact. `floatBitsToUint` is Cycles'
 * `__float_as_uint`. The float results are `float(hash) * 2^-32`, exactly Cycles'
 * `uint_to_float_incl` (1.0f / (float)0xFFFFFFFFu rounds to 2^-32).
 *
 * Names follow Cycles; GLSL vec2/vec3/vec4 stand for float2/float3/float4.
 * No globals, no #version: this file is #included (once) by the node libraries. */

#ifndef NODE_HASH_LIB
#define NODE_HASH_LIB

/* ---- Jenkins lookup3 (http://burtleburtle.net/bob/c/lookup3.c) ---- */

/* util/hash.h: #define rot(x, k) */
uint hash_rot(uint x, int k)
{
  return (x << k) | (x >> (32 - k));
}

/* util/hash.h: #define mix(a, b, c) (named hash_mix here: GLSL has a builtin mix()). */
void hash_mix(inout uint a, inout uint b, inout uint c)
{
  a -= c;
  a ^= hash_rot(c, 4);
  c += b;
  b -= a;
  b ^= hash_rot(a, 6);
  a += c;
  c -= b;
  c ^= hash_rot(b, 8);
  b += a;
  a -= c;
  a ^= hash_rot(c, 16);
  c += b;
  b -= a;
  b ^= hash_rot(a, 19);
  a += c;
  c -= b;
  c ^= hash_rot(b, 4);
  b += a;
}

/* util/hash.h: #define final(a, b, c) */
void hash_final(inout uint a, inout uint b, inout uint c)
{
  c ^= b;
  c -= hash_rot(b, 14);
  a ^= c;
  a -= hash_rot(c, 11);
  b ^= a;
  b -= hash_rot(a, 25);
  c ^= b;
  c -= hash_rot(b, 16);
  a ^= c;
  a -= hash_rot(c, 4);
  b ^= a;
  b -= hash_rot(a, 14);
  c ^= b;
  c -= hash_rot(b, 24);
}

/* util/hash.h: hash_uint() */
uint hash_uint(uint kx)
{
  uint a, b, c;
  a = b = c = 0xdeadbeefu + (1u << 2) + 13u;

  a += kx;
  hash_final(a, b, c);

  return c;
}

/* util/hash.h: hash_uint2() */
uint hash_uint2(uint kx, uint ky)
{
  uint a, b, c;
  a = b = c = 0xdeadbeefu + (2u << 2) + 13u;

  b += ky;
  a += kx;
  hash_final(a, b, c);

  return c;
}

/* util/hash.h: hash_uint3() */
uint hash_uint3(uint kx, uint ky, uint kz)
{
  uint a, b, c;
  a = b = c = 0xdeadbeefu + (3u << 2) + 13u;

  c += kz;
  b += ky;
  a += kx;
  hash_final(a, b, c);

  return c;
}

/* util/hash.h: hash_uint4() */
uint hash_uint4(uint kx, uint ky, uint kz, uint kw)
{
  uint a, b, c;
  a = b = c = 0xdeadbeefu + (4u << 2) + 13u;

  a += kx;
  b += ky;
  c += kz;
  hash_mix(a, b, c);

  a += kw;
  hash_final(a, b, c);

  return c;
}

/* ---- uint -> float ---- */

/* util/hash.h: uint_to_float_incl(): [0, uint_max] -> [0.0, 1.0]. */
float uint_to_float_incl(uint n)
{
  return float(n) * uintBitsToFloat(0x2f800000u); /* == 1.0f / (float)0xFFFFFFFFu == 2^-32 */
}

/* util/hash.h: uint_to_float_excl(): [0, uint_max] -> [0.0, 1.0). */
float uint_to_float_excl(uint n)
{
  return float(n) * uintBitsToFloat(0x2f7ffffeu); /* == 1.0f / 4294967808.0f */
}

/* util/hash.h: hash_uint_to_float() */
float hash_uint_to_float(uint kx)
{
  return uint_to_float_incl(hash_uint(kx));
}

/* util/hash.h: hash_uint2_to_float() */
float hash_uint2_to_float(uint kx, uint ky)
{
  return uint_to_float_incl(hash_uint2(kx, ky));
}

/* util/hash.h: hash_uint3_to_float() */
float hash_uint3_to_float(uint kx, uint ky, uint kz)
{
  return uint_to_float_incl(hash_uint3(kx, ky, kz));
}

/* util/hash.h: hash_uint4_to_float() */
float hash_uint4_to_float(uint kx, uint ky, uint kz, uint kw)
{
  return uint_to_float_incl(hash_uint4(kx, ky, kz, kw));
}

/* ---- float[234] -> float in [0, 1] ---- */

/* util/hash.h: hash_float_to_float() */
float hash_float_to_float(float k)
{
  return hash_uint_to_float(floatBitsToUint(k));
}

/* util/hash.h: hash_float2_to_float() */
float hash_float2_to_float(vec2 k)
{
  return hash_uint2_to_float(floatBitsToUint(k.x), floatBitsToUint(k.y));
}

/* util/hash.h: hash_float3_to_float() */
float hash_float3_to_float(vec3 k)
{
  return hash_uint3_to_float(floatBitsToUint(k.x), floatBitsToUint(k.y), floatBitsToUint(k.z));
}

/* util/hash.h: hash_float4_to_float() */
float hash_float4_to_float(vec4 k)
{
  return hash_uint4_to_float(
      floatBitsToUint(k.x), floatBitsToUint(k.y), floatBitsToUint(k.z), floatBitsToUint(k.w));
}

/* ---- float[234] -> float[234] ---- */

/* util/hash.h: hash_float2_to_float2() */
vec2 hash_float2_to_float2(vec2 k)
{
  return vec2(hash_float2_to_float(k), hash_float3_to_float(vec3(k.x, k.y, 1.0)));
}

/* util/hash.h: hash_float3_to_float3() */
vec3 hash_float3_to_float3(vec3 k)
{
  return vec3(hash_float3_to_float(k),
              hash_float4_to_float(vec4(k.x, k.y, k.z, 1.0)),
              hash_float4_to_float(vec4(k.x, k.y, k.z, 2.0)));
}

/* util/hash.h: hash_float4_to_float4() */
vec4 hash_float4_to_float4(vec4 k)
{
  return vec4(hash_float4_to_float(k),
              hash_float4_to_float(vec4(k.w, k.x, k.y, k.z)),
              hash_float4_to_float(vec4(k.z, k.w, k.x, k.y)),
              hash_float4_to_float(vec4(k.y, k.z, k.w, k.x)));
}

/* ---- float[1234] -> float3 ---- */

/* util/hash.h: hash_float_to_float3() */
vec3 hash_float_to_float3(float k)
{
  return vec3(hash_float_to_float(k),
              hash_float2_to_float(vec2(k, 1.0)),
              hash_float2_to_float(vec2(k, 2.0)));
}

/* util/hash.h: hash_float2_to_float3() */
vec3 hash_float2_to_float3(vec2 k)
{
  return vec3(hash_float2_to_float(k),
              hash_float3_to_float(vec3(k.x, k.y, 1.0)),
              hash_float3_to_float(vec3(k.x, k.y, 2.0)));
}

/* util/hash.h: hash_float4_to_float3() */
vec3 hash_float4_to_float3(vec4 k)
{
  return vec3(hash_float4_to_float(k),
              hash_float4_to_float(vec4(k.z, k.x, k.w, k.y)),
              hash_float4_to_float(vec4(k.w, k.z, k.y, k.x)));
}

/* ---- Hash Prospector / Wang (util/hash.h), for other node families ---- */

/* util/hash.h: hash_hp_uint() */
uint hash_hp_uint(uint i)
{
  i ^= i >> 16;
  i *= 0x21f0aaadu;
  i ^= i >> 15;
  i *= 0xd35a2d97u;
  i ^= i >> 15;
  return i ^ 0xe6fe3bebu;
}

/* util/hash.h: hash_hp_seeded_uint() */
uint hash_hp_seeded_uint(uint i, uint seed)
{
  seed ^= seed << 19;
  return hash_hp_uint(i ^ seed);
}

/* util/hash.h: hash_hp_float() */
float hash_hp_float(uint i)
{
  return uint_to_float_excl(hash_hp_uint(i));
}

/* util/hash.h: hash_hp_seeded_float() */
float hash_hp_seeded_float(uint i, uint seed)
{
  return uint_to_float_excl(hash_hp_seeded_uint(i, seed));
}

/* util/hash.h: hash_wang_seeded_uint() */
uint hash_wang_seeded_uint(uint i, uint seed)
{
  i = (i ^ 61u) ^ seed;
  i += i << 3;
  i ^= i >> 4;
  i *= 0x27d4eb2du;
  return i;
}

/* util/hash.h: hash_wang_seeded_float() */
float hash_wang_seeded_float(uint i, uint seed)
{
  return uint_to_float_excl(hash_wang_seeded_uint(i, seed));
}

#endif /* NODE_HASH_LIB */

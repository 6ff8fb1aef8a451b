"""Cryptomatte ids, manifests and metadata as Blender and Cycles write them.

Each object, material and asset (an object's top-most parent, or the
instancer's) is named by MurmurHash3_x86_32 (seed 0) of its name's UTF-8
bytes (blenkernel cryptomatte.cc, BKE_cryptomatte_hash); the renderer turns
the hash into the float the passes hold (Cycles' util_hash_to_float,
native/src/cryptomatte_module.cpp). The manifest maps each name to its hash
as 8 hex digits, and the render result carries, per layer,
``cryptomatte/<7 hex digits of the layer name's hash>/{name, hash,
conversion, manifest}`` (BKE_cryptomatte_meta_data_key), which is what the
compositor's Cryptomatte node and Nuke-style readers look for.
"""

import json

# (renderer layer name, ViewLayer flag)
KINDS = (("CryptoObject", "use_pass_cryptomatte_object"),
         ("CryptoMaterial", "use_pass_cryptomatte_material"),
         ("CryptoAsset", "use_pass_cryptomatte_asset"))
MAX_LEVELS = 16


def murmur3_32(data, seed=0):
    """MurmurHash3_x86_32 (Austin Appleby, public domain) of bytes."""
    c1, c2, mask = 0xCC9E2D51, 0x1B873593, 0xFFFFFFFF
    h = seed & mask
    n = len(data)
    blocks = n // 4
    for i in range(blocks):
        k = int.from_bytes(data[4 * i:4 * i + 4], "little")
        k = (k * c1) & mask
        k = ((k << 15) | (k >> 17)) & mask
        k = (k * c2) & mask
        h ^= k
        h = ((h << 13) | (h >> 19)) & mask
        h = (h * 5 + 0xE6546B64) & mask
    tail = data[4 * blocks:]
    k = 0
    if len(tail) >= 3:
        k ^= tail[2] << 16
    if len(tail) >= 2:
        k ^= tail[1] << 8
    if len(tail) >= 1:
        k ^= tail[0]
        k = (k * c1) & mask
        k = ((k << 15) | (k >> 17)) & mask
        k = (k * c2) & mask
        h ^= k
    h ^= n
    h ^= h >> 16
    h = (h * 0x85EBCA6B) & mask
    h ^= h >> 13
    h = (h * 0xC2B2AE35) & mask
    h ^= h >> 16
    return h


def name_hash(name):
    return murmur3_32(name.encode("utf-8"))


def enabled_layers(view_layer):
    """(layer names, Levels) the view layer asks for."""
    if view_layer is None:
        return [], 0
    names = [name for name, flag in KINDS if getattr(view_layer, flag, False)]
    levels = int(getattr(view_layer, "pass_cryptomatte_depth", 6))
    return names, max(1, min(levels, MAX_LEVELS))


def pass_names(layer, levels):
    """Blender's passes of one layer: two ranks (id, coverage) per RGBA pass."""
    return [f"{layer}{i:02d}" for i in range((levels + 1) // 2)]


def asset_object(inst, ob):
    """The asset of an instance: the top-most parent of the object, or of
    the instancer for an instance (Cycles' asset name)."""
    root = inst.parent if getattr(inst, "is_instance", False) and inst.parent is not None else ob
    root = getattr(root, "original", None) or root
    seen = 0
    while root.parent is not None and seen < 1000:  # parent loops are impossible; bounded anyway
        root = root.parent
        seen += 1
    return root


class Manifests:
    """Names met during export, per layer, and their hashes (cached)."""

    def __init__(self, layers):
        self.layers = list(layers)
        self._names = {layer: {} for layer in self.layers}
        self._cache = {}

    def wants(self, layer):
        return layer in self._names

    def hash(self, layer, name):
        h = self._cache.get(name)
        if h is None:
            h = self._cache[name] = name_hash(name)
        if layer in self._names:
            self._names[layer][name] = h
        return h

    def metadata(self, view_layer_name):
        """(key, value) pairs for RenderResult.stamp_data_add_field."""
        out = []
        for layer in self.layers:
            full = f"{view_layer_name}.{layer}"
            prefix = f"cryptomatte/{name_hash(full):08x}"[:len("cryptomatte/") + 7]
            manifest = {name: f"{h:08x}" for name, h in self._names[layer].items()}
            out += [(f"{prefix}/name", full), (f"{prefix}/hash", "MurmurHash3_32"),
                    (f"{prefix}/conversion", "uint32_to_float32"),
                    (f"{prefix}/manifest", json.dumps(manifest, separators=(",", ":")))]
        return out

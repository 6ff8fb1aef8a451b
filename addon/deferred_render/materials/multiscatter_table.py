"""Cycles 3.4: the Principled BSDF's mean under a uniform world with Multiscatter GGX over
GGX, by Metallic (rows) and Roughness (columns). Written by
tools/cycles_probe/probe_multiscatter.py --write (do not edit)."""

METALLIC = (0.0, 0.5, 1.0)
ROUGHNESS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
RATIO = (
    (1.0, 1.0001, 1.0001, 1.0014, 1.0042, 1.0086, 1.0129, 1.0166, 1.0186, 1.0185, 1.0177),
    (1.0, 1.0001, 1.0011, 1.0074, 1.0211, 1.0434, 1.0776, 1.118, 1.1578, 1.1893, 1.2109),
    (1.0, 1.0001, 1.0027, 1.0164, 1.0497, 1.1109, 1.2094, 1.3578, 1.574, 1.8807, 2.3111),
)

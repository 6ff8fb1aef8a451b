"""Node materials: Blender shader node trees -> the native renderer's graph IR.

``builder`` walks the tree (``graph`` follows groups, reroutes and mutes),
``nodes/`` holds one spec per Blender node (which GLSL function of
shaders/nodes/ it calls, with which arguments), ``images`` reads Blender
images into arrays. CONTRACT.md is the contract between specs and GLSL.
"""

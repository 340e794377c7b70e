"""Runnable examples: python -m brdfz.examples.mitsuba_sphere FILE.bsdf, python -m
brdfz.examples.realtime FILE (a sphere through the GPU shaders against the CPU reference)"""

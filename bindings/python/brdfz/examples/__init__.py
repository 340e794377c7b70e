"""Runnable examples: python -m brdfz.examples.mitsuba_sphere FILE.bsdf"""

"""How the smarticle stack is started: the sim-in-the-loop demo and the tools that join packages.

This package sits on top of the others (it imports the sim, tracking, feedback and bags packages and
nothing imports it): ``demo`` runs the whole stack in separate processes; ``sim_camera`` calibrates the
overhead tracker against the simulated camera.
"""

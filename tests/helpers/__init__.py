"""Test helpers, in one place: ROS spinning, the board emulator, the hardware rig, glider scenes."""

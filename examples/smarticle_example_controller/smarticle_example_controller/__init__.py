"""An example of a user's own smarticle controller (docs/own_controller.md)."""

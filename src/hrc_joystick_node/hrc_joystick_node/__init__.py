"""The human side of hrc: joystick device, /joy adapter, simulated human, human node."""

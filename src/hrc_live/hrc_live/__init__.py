"""Live hrc sessions with a person: display, joystick set-up helper, operator controls."""

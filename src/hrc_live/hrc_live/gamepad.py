"""The person's gamepad through the browser: what the page sends, as the joy convention (pure).

The person's page reads a gamepad with the browser's Gamepad API (any gamepad the browser
knows, with no driver or joystick device on the computer) and, while one is connected, sends
the stick the person chose by moving it to ``POST /gamepad`` with the page's session token: at
once when it moved (it looks every 5 ms), every 50 ms when it did not. The display node
publishes each as ``sensor_msgs/Joy`` on ``/joy`` and the human node takes it with ``input:
joy`` and the guarantees of a joystick: the person's input only while messages come, a
silent ``/joy`` (the gamepad unplugged, the page closed) is a lost input that pauses the
session with the same words, never a silent stand-in.

Body: ``{"axis": value in [-1, 1], "button": bool, "axis_index": int, "id": text}``: the
chosen axis as the browser reports it (the standard mapping: stick up or left is -1), the
first button (the enable button, when the human node asks for one), which axis the person
chose and the gamepad's name (for the log). The joy convention is the other way round (stick
up or left is +1, as the ``joy`` node publishes it): :func:`joy_values` flips the axis.
"""

import json
import math

MAX_ID_CHARACTERS = 200


def gamepad_body(body: bytes) -> tuple:
    """Return (record, '') of a /gamepad body, or (None, every reason it is refused)."""
    try:
        record = json.loads(body or b'{}')
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None, 'not JSON'
    if not isinstance(record, dict):
        return None, 'not a JSON object {"axis", "button", "axis_index", "id"}'
    reasons = []
    axis = record.get('axis')
    if isinstance(axis, bool) or not isinstance(axis, (int, float)) or not math.isfinite(axis) \
            or not -1.0 <= axis <= 1.0:
        reasons.append(f'axis must be a number in [-1, 1], got {str(axis)[:40]!r}')
    if not isinstance(record.get('button', False), bool):
        reasons.append('button must be true or false')
    index = record.get('axis_index', 0)
    if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < 64:
        reasons.append(f'axis_index must be an integer in 0..63, got {str(index)[:40]!r}')
    name = record.get('id', '')
    if not isinstance(name, str) or len(name) > MAX_ID_CHARACTERS:
        reasons.append(f'id must be a text of at most {MAX_ID_CHARACTERS} characters')
    if reasons:
        return None, '; '.join(reasons)
    return record, ''


def joy_values(record: dict) -> tuple:
    """Return (axes, buttons) of the Joy message for a checked record (the joy convention).

    The chosen stick is axis 0 (``hrc session --human gamepad`` sets ``human.axis: 0``), the
    enable button button 0.
    """
    return [-float(record['axis'])], [int(bool(record.get('button', False)))]

"""The ``--set NODE.PARAM=VALUE`` overrides of the session and experiment commands."""

from hrc_bringup.plan import parse_override


def parse_overrides(texts) -> dict:
    """Return {'node.name': value} of ``--set`` texts (a later one wins).

    Raises ValueError with the reason of every text that is not ``node.parameter=value``.
    """
    overrides, reasons = {}, []
    for text in texts:
        try:
            node, name, value = parse_override(text)
        except ValueError as error:
            reasons.append(str(error))
            continue
        overrides[f'{node}.{name}'] = value
    if reasons:
        raise ValueError('; '.join(reasons))
    return overrides

"""Built-in controllers: components from measurements (signal links) to commands."""
from __future__ import annotations

from ..errors import did_you_mean


def read(c, inst, key: str) -> str:
    """The expression of the measurement linked as inputs[key]: a value of this step if a kind
    computed it already (set-points, weather), else its signal (end of the last step)."""
    name = inst.options["inputs"].get(key)
    if not isinstance(name, str):
        c.problems.append(f"{inst.where} inputs.{key}: missing; link it to a signal, e.g. "
                          f"inputs = {{ {key} = \"storage.T_sensor_10\" }}")
        return "0.0"
    return c.values.get(name) or c.s(name)


def write(c, inst, key: str, expr: str, phase: str = "control") -> None:
    """Write the controller output `key` to the input it is linked to (unless driven remotely);
    a link may scale: { signal = "heat_pump.on", scale = 0.1 }."""
    link = inst.options["outputs"].get(key)
    if link is None:
        return  # an output nobody listens to
    scale = None
    if isinstance(link, dict):
        link, scale = link.get("signal"), link.get("scale")
    if not isinstance(link, str) or (scale is not None and not isinstance(scale, (int, float))):
        c.problems.append(f"{inst.where} outputs.{key} = {inst.options['outputs'][key]!r}: expected "
                          "\"component.input\" or { signal = \"component.input\", scale = 0.1 }")
        return
    c.write_command(phase, link, f"{expr} * {float(scale)!r}" if scale is not None else expr)


def emit_step(c, kind, inst, module: str, args: list[str] | None = None) -> str:
    """A controller's step in the control phase: `module`.step(h, state, parameters, *inputs)
    returns its OUTPUTS in order, each written to the input it links. `args` replaces the linked
    inputs (a kind passing placeholders for unused parts); returns the state array's name, which
    the kind's own signals read."""
    from ..component import pack

    x, p = c.state(inst, kind.initial_state(inst)), c.param(inst, pack(inst.params))
    if args is None:
        args = [read(c, inst, k) for k in kind.INPUTS]
    outs = [c.var(v) for v in kind.OUTPUTS]
    c.emit("control", f"{', '.join(outs)} = {c.module(module)}.step(h, {x}, {p}, {', '.join(args)})")
    for key, v in zip(kind.OUTPUTS, outs):
        write(c, inst, key, v)
    return x


def check_keys(c, inst, inputs: tuple, outputs: tuple) -> None:
    for table, allowed in (("inputs", inputs), ("outputs", outputs)):
        for key in inst.options[table]:
            if key not in allowed:
                c.problems.append(f"{inst.at(table)}.{key}: not a {table[:-1]} of a {inst.kind} "
                                  "controller; " + did_you_mean(key, allowed, f"allowed: {', '.join(allowed)}", n=2))

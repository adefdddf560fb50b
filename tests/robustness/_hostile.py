"""Generated hostile inputs (shared by tests/robustness and benchmarks/fuzz_entry.py): YAML that
expands to an unbounded size (alias bombs, deep nesting, many nodes), integer literals with
thousands of digits and coordinates near the float limit, each placed in a field of a scenario."""

from __future__ import annotations

from hypothesis import strategies as st

from viapath.io.safe_read import MAX_YAML_DEPTH, MAX_YAML_NODES

SCENARIO_HEAD = "name: hostile\nrobot: {start: [0, 0]}\npath: {waypoints: [[0, 0], [5, 0]], half_width: 1.0}\n"

#: Where a hostile value goes: a YAML key at the top level (the value is indented under it).
FIELDS = ("obstacles", "description", "walls", "planner", "extra", "perception")


@st.composite
def alias_bombs(draw) -> str:
    """A "billion laughs": ``levels`` anchors, each a list of ``fan`` aliases of the one before, so a
    dozen lines expand to fan**levels values (always past the node cap), under some field."""
    fan = draw(st.integers(2, 12))
    levels = 1
    while fan**levels <= 4 * MAX_YAML_NODES:
        levels += 1
    levels += draw(st.integers(0, 3))
    flow = draw(st.booleans())
    lines = [f"l0: &l0 [{', '.join(['lol'] * fan)}]"] if flow else ["l0: &l0 lol"]
    for level in range(1, levels + 1):
        lines.append(f"l{level}: &l{level} [{', '.join([f'*l{level - 1}'] * fan)}]")
    field = draw(st.sampled_from(FIELDS))
    key_first = draw(st.booleans())
    bomb = "\n".join(lines) + f"\n{field}: *l{levels}\n"
    return bomb + SCENARIO_HEAD if key_first else SCENARIO_HEAD + bomb


@st.composite
def deep_nesting(draw) -> str:
    depth = draw(st.integers(MAX_YAML_DEPTH + 1, 5000))
    kind = draw(st.sampled_from(["flow-list", "flow-map", "block-list"]))
    if kind == "flow-list":
        value = "[" * depth + "1" + "]" * depth
    elif kind == "flow-map":
        value = "{a: " * depth + "1" + "}" * depth
    else:
        value = (
            "\n" + "".join("  " * (i + 1) + "-\n" for i in range(min(depth, 400) - 1)) + "  " * min(depth, 400) + "- 1"
        )
    return SCENARIO_HEAD + f"{draw(st.sampled_from(FIELDS))}: {value}\n"


@st.composite
def many_nodes(draw) -> str:
    count = draw(st.integers(MAX_YAML_NODES + 1, 3 * MAX_YAML_NODES))
    return SCENARIO_HEAD + f"obstacles: [{','.join(['0'] * count)}]\n"


@st.composite
def long_integers(draw) -> tuple[str, str]:
    """(scenario text, the field holding an integer literal of thousands of digits)."""
    digits = draw(st.integers(20, 20000))
    sign = draw(st.sampled_from(["", "-", "+"]))
    literal = sign + draw(st.sampled_from("123456789")) + "0" * (digits - 1)
    where = draw(
        st.sampled_from(
            [
                ("robot: {start: [%s, 0]}", "robot.start.0"),
                ("seed: %s", "seed"),
                ("duration_s: %s", "duration_s"),
                ("obstacles: [{start: [1, %s], velocity: [0, 0]}]", "obstacles.0.start.1"),
                ("planner: {name: viapath, max_depth: %s}", "planner.max_depth"),
            ]
        )
    )
    text = "name: big\npath: {waypoints: [[0, 0], [5, 0]], half_width: 1.0}\n" + (where[0] % literal) + "\n"
    if not where[0].startswith("robot"):
        text += "robot: {start: [0, 0]}\n"
    return text, where[1]


@st.composite
def far_coordinates(draw) -> tuple[str, str]:
    """(scenario text, field) with one coordinate between 1e7 and the float limit (or its negative)."""
    value = draw(st.floats(1e7, 1.7e308)) * draw(st.sampled_from([1, -1]))
    where = draw(
        st.sampled_from(
            [
                ("robot: {start: [%r, 0]}", "robot.start.0"),
                ("path: {waypoints: [[0, 0], [%r, 1]], half_width: 1.0}", "path.waypoints.1.0"),
                ("obstacles: [{start: [1, %r], velocity: [0, 0]}]", "obstacles.0.start.1"),
                ("walls: [[[0, 1], [%r, 1]]]", "walls.0.1.0"),
            ]
        )
    )
    text = "name: far\n" + (where[0] % value) + "\n"
    if not where[0].startswith("robot"):
        text += "robot: {start: [0, 0]}\n"
    if not where[0].startswith("path"):
        text += "path: {waypoints: [[0, 0], [5, 0]], half_width: 1.0}\n"
    return text, where[1]


def hostile_yaml():
    """Any text of the oversized kinds (each must be refused quickly with a short message)."""
    return st.one_of(alias_bombs(), deep_nesting(), many_nodes())


@st.composite
def option_values(draw, options) -> dict:
    """Values for a random subset of ``options`` (an OptionSet), each inside its own bounds, often at
    an end of them: what the schema accepts must give a cycle of bounded work."""
    values = {}
    for option in options:
        if not draw(st.booleans()):
            continue
        if option.choices:
            values[option.path] = draw(st.sampled_from(option.choices))
        elif option.kind is bool:
            values[option.path] = draw(st.booleans())
        elif option.kind in (int, float, tuple):
            low = option.minimum if option.minimum is not None else 0.0
            high = option.maximum
            if option.kind is int:
                number = st.sampled_from([int(low), int(high)]) | st.integers(int(low), int(high))
            else:
                inner = low * 1.001 + 1e-6 if option.exclusive_minimum else low
                number = st.sampled_from([inner, high]) | st.floats(inner, high)
            if option.kind is tuple:
                values[option.path] = draw(st.lists(number, min_size=1, max_size=8))
            else:
                values[option.path] = draw(number)
    return values

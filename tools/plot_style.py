"""One colour, marker and label per engine and scheme, for every figure in tools/ (issue 16).

The FPS plots coloured engines by their position in the run's engine list, so blue was the
default scheme in fps_*.png and the quadrants scheme in clumped/; now a name has one colour and
one label wherever it is drawn (bench_report.py, accuracy_report.py).
"""

import zlib

# Quadrant's default scheme is the deterministic one: "quadrant" and "quadrant:deterministic"
# are the same engine and look the same.
STYLES = {
    "quadrant": ("tab:blue", "o", "Quadrant (deterministic scheme)"),
    "quadrant:quadrants": ("tab:orange", "s", "Quadrant (quadrants scheme, thesis)"),
    "box2d": ("tab:green", "^", "Box2D 2.4.1"),
    "bullet": ("tab:red", "D", "Bullet 3.24 (2D)"),
    "chipmunk": ("tab:purple", "v", "Chipmunk 7"),
}
# Other variants (quadrant:soft_step+sub4, ...): a colour picked by a stable hash of the name.
EXTRA_COLOURS = ["tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray", "gold", "navy", "teal"]
EXTRA_MARKERS = ["P", "X", "*", "h", "<", ">"]
# Thread counts: one line style each, the same in every figure.
THREAD_STYLES = {1: "-", 2: "--", 3: "-.", 4: ":"}


def canonical(engine):
    """The style key: "quadrant:deterministic" (and an empty variant) is "quadrant"."""
    base, _, variant = engine.partition(":")
    if base == "quadrant" and variant in ("", "deterministic"):
        return "quadrant"
    return engine


def style(engine):
    """(colour, marker, label) of an engine name."""
    key = canonical(engine)
    if key in STYLES:
        return STYLES[key]
    h = zlib.crc32(key.encode())
    base, _, variant = key.partition(":")
    label = f"Quadrant ({variant})" if base == "quadrant" else key
    return EXTRA_COLOURS[h % len(EXTRA_COLOURS)], EXTRA_MARKERS[h % len(EXTRA_MARKERS)], label


def thread_style(threads):
    return THREAD_STYLES.get(threads, (0, (1, 1 + threads)))

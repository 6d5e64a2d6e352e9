"""``warpcloth scene list | show``: the bundled scenes, as templates to copy."""

from __future__ import annotations

import argparse
import importlib.resources

from warpcloth.errors import OptionError

from .options import add_overwrite, new_file, path_text


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``scene list`` and ``scene show``."""
    scene_p = sub.add_parser("scene", help="the bundled scenes: list them, or print one (with its comments)")
    scene_sub = scene_p.add_subparsers(dest="scene_command", required=True)
    scene_sub.add_parser("list", help="bundled scene names and what each is").set_defaults(handler=list_command)
    show_p = scene_sub.add_parser("show", help="print a bundled scene file, ready to copy and edit")
    show_p.add_argument("name", metavar="NAME", help="a bundled scene (warpcloth scene list)")
    show_p.add_argument("-o", "--output", type=path_text, help="write it to this .toml file instead of printing it")
    add_overwrite(show_p, "file -o")
    show_p.set_defaults(handler=show_command)


def _text(name: str) -> str:
    from warpcloth.scene import bundled_scenes

    resource = importlib.resources.files("warpcloth.scenes") / f"{name}.toml"
    if name not in bundled_scenes() or not resource.is_file():
        raise OptionError("NAME", f"no bundled scene {name!r} (bundled: {', '.join(bundled_scenes())})")
    return resource.read_text(encoding="utf-8")


def list_command(args: argparse.Namespace) -> int:
    """One line per bundled scene: its name and the first line of its comment."""
    from warpcloth.scene import bundled_scenes

    for name in bundled_scenes():
        first = next((line.lstrip("# ").strip() for line in _text(name).splitlines() if line.startswith("#")), "")
        print(f"{name}: {first}")
    return 0


def show_command(args: argparse.Namespace) -> int:
    """Print (or write) a bundled scene's file as it ships, comments included."""
    text = _text(args.name)
    if args.output is None:
        print(text, end="")
        return 0
    out = new_file(args.output, args.overwrite, "-o")
    if out.suffix != ".toml":
        raise OptionError("-o", f"{out} must end in .toml (a scene file is read as a path by that suffix)")
    from warpcloth.io.atomic import write_text_atomically

    write_text_atomically(out, text)
    print(f"wrote {out} (run it with: warpcloth run {out})")
    return 0

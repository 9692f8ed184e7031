"""`cargo` as the README's and the guide's commands use it, standing for the tests' own builds
when tests/guide_commands.rs runs those commands: `install --path P [--bin B]`, `build -p P` and
`add --path P` check that the package holds the program (cargo's own metadata says); `run [-p P]
[--bin B] -- ARGS` runs the tests' build of that program with ARGS (with `--help` added, its
output dropped, when PVT3_GUIDE_HELP is set: a parse-only block). Anything else is refused, so
that a page naming another cargo command fails until the test knows what it means.

    PVT3_REAL_CARGO=CARGO PVT3_WORKSPACE=ROOT PVT3_BUILT=DIR guide_cargo.py COMMAND ARGS…
"""

import json
import os
import subprocess
import sys


def metadata(manifest):
    # The real path: cargo finds a member's workspace among its folder's parents.
    args = [os.environ["PVT3_REAL_CARGO"], "metadata", "--no-deps", "--offline", "--format-version", "1", "--manifest-path", os.path.realpath(manifest)]
    return json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)


def fail(why):
    print(f"cargo (as the tests stand it in): {why}", file=sys.stderr)
    sys.exit(101)


def program(package, wanted):
    """The binary `wanted` of `package` (its only or default one when None), built by the tests."""
    bins = [t["name"] for t in package["targets"] if "bin" in t["kind"]]
    name = wanted or package.get("default_run") or (bins[0] if len(bins) == 1 else None)
    if name not in bins:
        fail(f"package {package['name']} has no binary {wanted or '(a default one)'}: it has {', '.join(bins) or 'none'}")
    built = os.path.join(os.environ["PVT3_BUILT"], name)
    if not os.access(built, os.X_OK):
        fail(f"{built}: the tests did not build {name}")
    return built


def main(command, *args):
    words, after = (list(args), [])
    if "--" in words:
        i = words.index("--")
        words, after = words[:i], words[i + 1 :]
    options, flags = {}, set()
    it = iter(words)
    for w in it:
        if w in ("--path", "-p", "--package", "--bin"):
            options[w.replace("--package", "-p")] = next(it, None)
        elif w.startswith("-"):
            flags.add(w)
        else:
            fail(f"{command}: an argument {w!r} the guide's commands do not use")
    if "--path" in options:
        path = options["--path"]
        if not os.path.isfile(os.path.join(path, "Cargo.toml")):
            fail(f"--path {path}: no Cargo.toml there")
        packages = metadata(os.path.join(path, "Cargo.toml"))["packages"]
        package = next(p for p in packages if os.path.realpath(os.path.dirname(p["manifest_path"])) == os.path.realpath(path))
    else:
        workspace = metadata(os.path.join(os.environ["PVT3_WORKSPACE"], "Cargo.toml"))
        name = options.get("-p")
        members = workspace["workspace_default_members"] if name is None else workspace["workspace_members"]
        found = [p for p in workspace["packages"] if p["id"] in members and (name is None or p["name"] == name)]
        if len(found) != 1:
            fail(f"-p {name}: no such package in the workspace" if name else "more than one default package")
        package = found[0]
    if command in ("install", "build", "add"):
        if command != "add":
            program(package, options.get("--bin"))
        return
    if command == "run":
        built = program(package, options.get("--bin"))
        if os.environ.get("PVT3_GUIDE_HELP"):  # a parse-only block: the command line read, no work done
            after.append("--help")
            os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
        os.execv(built, [built, *after])
    fail(f"`cargo {command}`: not a command the guide's pages use")


if __name__ == "__main__":
    main(*sys.argv[1:])

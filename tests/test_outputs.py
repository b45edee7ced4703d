"""Output files of the command line: no file is ever replaced without ``--force``, whatever
the command and the option (one check, `empact.cli._common.check_outputs`, before any work);
the format follows the suffix, and a ``--format`` must match it."""
import click
import pytest
from click.testing import CliRunner

from empact.cli import main
from empact.cli._common import OutputFile

#: output options by name: what any option that writes a file is called
WRITING = ("--out", "--json-out", "--plot", "--csv")


def _commands(group=main, ctx=None, path=()):
    """Every command of the CLI tree: (path, command)."""
    ctx = ctx or click.Context(main)
    for name in group.list_commands(ctx):
        cmd = group.get_command(ctx, name)
        if isinstance(cmd, click.Group):
            yield from _commands(cmd, ctx, path + (name,))
        else:
            yield path + (name,), cmd


COMMANDS = list(_commands())
OUTPUTS = [(path, p) for path, cmd in COMMANDS for p in cmd.params
           if isinstance(p.type, OutputFile)]


def test_every_file_output_is_checked():
    """An option that writes a file is an `OutputFile` (checked before the command runs), and
    a command with one has --force; a folder option is a folder (checked by output_folder)."""
    assert len(OUTPUTS) >= 30, len(OUTPUTS)
    for path, cmd in COMMANDS:
        for p in cmd.params:
            if not isinstance(p, click.Option) or not set(p.opts) & set(WRITING):
                continue
            folder = isinstance(p.type, click.Path) and not p.type.file_okay
            assert isinstance(p.type, OutputFile) or folder, (path, p.opts)
        if any(isinstance(p.type, OutputFile) for p in cmd.params):
            assert "force" in {p.name for p in cmd.params}, path


def _args(cmd, tested, out_name):
    """The command's required arguments and options (dummy values: the output check comes
    first) and the tested output option."""
    args = []
    for p in cmd.params:
        if p is tested or not p.required:
            continue
        if isinstance(p.type, OutputFile):
            value = f"fresh.{(p.type.suffixes or ('x',))[0]}"
        elif isinstance(p.type, click.Choice):
            value = p.type.choices[0]
        else:
            value = "x"
        args += [value] if isinstance(p, click.Argument) else [p.opts[0], value]
    return args + [max(tested.opts, key=len), out_name]


@pytest.mark.parametrize("path, param", OUTPUTS,
                         ids=[" ".join(c) + " " + max(p.opts, key=len) for c, p in OUTPUTS])
def test_an_existing_file_is_never_replaced_without_force(tmp_path, monkeypatch, path, param):
    monkeypatch.chdir(tmp_path)
    suffix = (param.type.suffixes or ("dat",))[0]
    mine = tmp_path / f"mine.{suffix}"
    mine.write_text("precious")
    res = CliRunner().invoke(main, [*path, *_args(_sub(path), param, mine.name)])
    option = max(param.opts, key=len)
    assert res.exit_code == 2, res.output
    assert res.output == f"error: {option} {mine.name}: exists; give --force to replace it\n"
    assert mine.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == [mine.name]


def _sub(path):
    cmd = main
    for name in path:
        cmd = cmd.get_command(click.Context(cmd), name)
    return cmd


@pytest.mark.parametrize("args, match", [
    (["linearize", "--format", "mat", "--out", "plant.npz"],
     "--out plant.npz: file suffix '.npz' does not match --format mat (name the file "
     "plant.mat"),
    (["linearize", "--format", "npz", "--out", "plant"], "file suffix 'none' does not match"),
    (["modes", "driveline", "--json-out", "modes.txt"],
     "--json-out modes.txt: file suffix '.txt' must be one of .json"),
    (["control", "design", "--out", "c.json", "--json-out", "c.json"],
     "--json-out c.json: the same file as --out; give each output its own file"),
    (["nmp", "--plot", "z.png", "--json-out", "./z.png"], "file suffix '.png' must be one"),
    (["rig", "--out", "rec.txt"], "--out rec.txt: file suffix '.txt' must be one of .csv"),
    (["calibrate", "t.toml", "--out", "c.json"], "--out c.json: file suffix '.json' must be "
                                                 "one of .toml"),
    (["control", "simulate", "--example", "x", "--out", "run.json"],
     "--out run.json: file suffix '.json' must be one of .csv"),
])
def test_the_format_follows_the_suffix(tmp_path, monkeypatch, args, match):
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, res.output
    assert res.output.startswith("error: ") and match in res.output, res.output
    assert list(tmp_path.iterdir()) == []


def test_force_replaces_the_file(tmp_path):
    out = tmp_path / "modes.json"
    out.write_text("old")
    res = CliRunner().invoke(main, ["modes", "driveline", "--json-out", str(out), "--force"])
    assert res.exit_code == 0, res.output
    assert out.read_text().startswith("{")

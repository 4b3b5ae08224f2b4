"""The command line's words before Hydra reads them: every reading of ``argv`` tcbench does
itself. A key=value command's flags, positional file and ``key=value`` words turned into Hydra
overrides that mean what the user typed (:func:`app_words`); ``tcbench run``'s flags checked
(:func:`run_flags`); ``tcbench leaderboard``'s flags as its keys (:func:`leaderboard_words`);
``tcbench help COMMAND`` (:func:`command_words`); and what a sweep's overrides ask of Hydra
(:func:`asks_info`, :func:`configs_elsewhere`, :func:`given`)."""

from __future__ import annotations

import os
from collections.abc import Container
from dataclasses import dataclass

from tcbench.cli.flags import (
    CFG_CHOICES,
    CONFIG_SOURCE_FLAGS,
    HELP_FLAGS,
    HYDRA_FLAGS,
    HYDRA_INFO_FLAGS,
    KEY_FLAGS,
    VALUE_FLAGS,
)
from tcbench.commands.registry import SPECS


class UserError(Exception):
    """A mistake in what the user asked for: reported in one line, exit code 2."""


def command_words(argv: list[str], commands: Container[str]) -> list[str]:
    """``argv`` with ``help COMMAND`` read as ``COMMAND --help``."""
    if len(argv) == 2 and argv[0] == "help" and argv[1] in commands:  # tcbench help simulate
        return [argv[1], "--help"]
    return argv


def flag_name(arg: str) -> str | None:
    """The option an argument is (``--cfg=job`` is ``--cfg``), or None for ``key=value``."""
    return arg.split("=", 1)[0] if arg.startswith("-") else None


def unknown_option(command: str, flag: str) -> UserError:
    return UserError(f"unknown option {flag!r} for tcbench {command}; see `tcbench {command} --help`")


@dataclass(frozen=True)
class AppWords:
    """A key=value command's command line as read: ``help`` (``-h``/``--help``: nothing else is
    read), the Hydra overrides, ``cfg`` (``--cfg job``, else None) and whether ``-m`` sweeps.
    The overrides of one job (no ``-m``, or ``--cfg``) are literal strings
    (:func:`_hydra_value`); a sweep's are Hydra's grammar."""

    help: bool = False
    overrides: tuple[str, ...] = ()
    cfg: str | None = None
    multirun: bool = False

    @property
    def sweeps(self) -> bool:
        """A ``-m`` sweep to run (not ``--cfg job``, which prints one config)."""
        return self.multirun and self.cfg is None


def app_words(command: str, argv: list[str]) -> AppWords:
    """The command line of the key=value command ``command``: its flags (``--out DIR`` and the
    other :data:`~tcbench.cli.flags.KEY_FLAGS`, ``--cfg job``, ``-m``), its positional file
    argument, its ``key=value`` words checked (a file named ``a=b.csv`` is not a key) and
    rewritten for Hydra (:func:`_open_key`, :func:`_literal_path`, :func:`_hydra_value`); a
    :class:`UserError` for anything else."""
    if any(a in HELP_FLAGS for a in argv):  # the help of the schema: nothing else imported
        return AppWords(help=True)
    args, flagged, cfg, multirun = _flags(command, argv)
    positional = SPECS[command].positional
    if positional and args and "=" not in args[0]:
        args = [f"{positional}={args[0]}", *args[1:]]
    args += flagged
    if bad := [a for a in args if "=" not in a or a.startswith("=")]:
        raise UserError(f"expected key=value, got {bad[0]!r}")
    if named := [a for a in args if _file_not_key(a, command)]:
        key, _, _ = named[0].partition("=")
        given_as = positional or _first_input_key(command)
        raise UserError(f"{named[0]}: {key!r} is no key of tcbench {command}, and {named[0]} is a file; to read it, "
                        f"give {given_as}={named[0]}")
    if nul := [a for a in args if "\0" in a]:
        raise UserError(f"{nul[0].split('=', 1)[0]}=: holds a NUL character")
    args = [_literal_path(_open_key(a, command), command, multirun) for a in args]
    if not (multirun and cfg is None):
        args = [_hydra_value(a) for a in args]
    return AppWords(False, tuple(args), cfg, multirun)


def _flags(command: str, argv: list[str]) -> tuple[list[str], list[str], str | None, bool]:
    """The words of ``argv`` that are no flag, the ``key=value`` of its key flags (read after the
    positional argument), its ``--cfg`` value and whether it has ``-m``."""
    args: list[str] = []
    flagged: list[str] = []  # key=value of KEY_FLAGS, after the positional argument is read
    cfg: str | None = None
    multirun = False
    keys = _schema_keys(command)
    it = iter(argv)
    for a in it:
        flag = flag_name(a)
        if flag is None:
            args.append(a)
        elif flag in KEY_FLAGS and KEY_FLAGS[flag][0] in keys:
            value = a.split("=", 1)[1] if "=" in a else next(it, None)
            if value is None:
                raise UserError(f"{flag} needs a value ({flag} {KEY_FLAGS[flag][1]}); see `tcbench {command} --help`")
            flagged.append(f"{KEY_FLAGS[flag][0]}={value}")
        elif flag in {"--cfg", "-c"}:
            cfg = a.split("=", 1)[1] if "=" in a else next(it, None)
            if cfg != "job":
                what = f"--cfg {cfg}" if cfg else "--cfg without a value"
                raise UserError(f"{what}: tcbench {command} prints only its job config; use --cfg job")
        elif flag in {"-m", "--multirun"}:
            multirun = True
        else:
            raise unknown_option(command, flag)
    return args, flagged, cfg, multirun


def _hydra_value(arg: str) -> str:
    """``key=value`` as Hydra's override grammar reads it as that literal string: quoted when
    the value would not parse (``out=run(1)``) or would be a sweep (``drop=a,b``). One job only:
    with ``-m`` the user writes Hydra's grammar (``recording=a.csv,b.csv`` sweeps)."""
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    key, _, value = arg.partition("=")
    try:
        (override,) = OverridesParser.create().parse_overrides([arg])
        if not override.is_sweep_override():
            return arg
    except HydraException:
        pass
    from tcbench.cli.app import hydra_string

    return f"{key}={hydra_string(value)}"


def _open_key(arg: str, command: str) -> str:
    """``protocol_params.duration_s=3600`` as ``++protocol_params.duration_s=3600``: a key inside a
    free-form dict of the schema (``protocol_params``, ``effects``) is added or replaced."""
    import dataclasses

    if arg.startswith(("+", "~")):
        return arg
    open_dicts = {f.name for f in dataclasses.fields(SPECS[command].schema_class()) if str(f.type).startswith("dict")}
    return f"++{arg}" if arg.split("=", 1)[0].split(".", 1)[0] in open_dicts and "." in arg.split("=", 1)[0] else arg


def _schema_keys(command: str) -> set[str]:
    """The top-level keys of ``command``'s schema."""
    import dataclasses

    return {f.name for f in dataclasses.fields(SPECS[command].schema_class())}


def _first_input_key(command: str) -> str:
    """The first file argument of ``command`` (``recording``, ``csv``), or ``recording``."""
    return next(iter(SPECS[command].inputs), "recording")


def _file_not_key(arg: str, command: str) -> bool:
    """True when ``arg`` is no ``key=value`` of ``command`` (its key is none of the schema's) but
    the name of a file: ``tcbench metrics a=b.csv`` means the file ``a=b.csv``."""
    import dataclasses

    head = arg.partition("=")[0].lstrip("+~").split(".", 1)[0]
    known = {f.name for f in dataclasses.fields(SPECS[command].schema_class())} | {"hydra"}
    return head not in known and os.path.lexists(arg)


def _literal_path(arg: str, command: str, multirun: bool) -> str:
    """A file argument of ``command`` (``recording=``, ``csv=``, ``model=``, ``test_recordings=``)
    quoted and escaped so that Hydra and OmegaConf pass its text on as it is: a name holding ``$``,
    ``${...}``, commas or brackets is the file's name, never an interpolation or a sweep. One job
    takes the whole text as the path (unquoted when it is quoted; a list key: its items, in Hydra's
    list syntax); with ``-m`` Hydra's grammar still separates the values (``recording=a.csv,b.csv``),
    each then literal. ``null`` stays null."""
    import dataclasses

    key, eq, value = arg.partition("=")
    if not eq or key not in SPECS[command].inputs or value == "null":
        return arg
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.core.override_parser.types import ChoiceSweep
    from hydra.errors import HydraException

    from tcbench.cli.app import hydra_string
    from tcbench.commands.schemas import literal

    listed = any(f.name == key and str(f.type).startswith("list")
                 for f in dataclasses.fields(SPECS[command].schema_class()))
    quoted = len(value) > 1 and value[0] == value[-1] and value[0] in "'\""
    if not multirun and not listed and not quoted:
        return f"{key}={hydra_string(literal(value))}"
    try:
        (override,) = OverridesParser.create().parse_overrides([arg])
    except HydraException:
        return arg  # Hydra's own line names the problem
    parsed = override.value()
    items = parsed.list if isinstance(parsed, ChoiceSweep) else parsed if isinstance(parsed, list) else [parsed]
    if not all(isinstance(v, str) for v in items):
        return arg
    quoted = [hydra_string(literal(v)) for v in items]
    if isinstance(parsed, list) and not isinstance(parsed, ChoiceSweep):
        return f"{key}=[{','.join(quoted)}]"
    return f"{key}={','.join(quoted)}"


def run_flags(args: list[str]) -> set[str]:
    """The Hydra flags of ``tcbench run``'s command line (a flag's value skipped); a
    :class:`UserError` for any other flag or a ``--cfg`` without one of Hydra's values."""
    after_value_flag, flags = False, set()
    for a in args:
        if not after_value_flag and (flag := flag_name(a)) is not None:
            if flag not in HYDRA_FLAGS:
                raise unknown_option("run", flag)
            flags.add(flag)
        after_value_flag = a in VALUE_FLAGS
    _check_cfg_value(args)
    return flags


def _check_cfg_value(args: list[str]) -> None:
    """A UserError for ``--cfg`` (``-c``) without one of Hydra's values (job, hydra, all)."""
    for i, a in enumerate(args):
        flag, eq, value = a.partition("=")
        if flag not in {"--cfg", "-c"}:
            continue
        given_value = value if eq else (args[i + 1] if i + 1 < len(args) else None)
        if given_value not in CFG_CHOICES:
            what = f"--cfg {given_value}" if given_value else "--cfg without a value"
            raise UserError(f"{what}: expected {', '.join(CFG_CHOICES[:-1])} or {CFG_CHOICES[-1]}")


def shows_run_help(flags: set[str]) -> bool:
    """Whether ``tcbench run`` prints its own help: ``-h``/``--help`` with the configs its own
    (from elsewhere, Hydra's help)."""
    return bool(HELP_FLAGS & flags) and not CONFIG_SOURCE_FLAGS & flags


# ``tcbench leaderboard``'s flags, kept as aliases of its keys
LEADERBOARD_FLAGS = {"--experiment": "experiments", "--sweep": "sweep", "--tracking-uri": "tracking.uri"}


def leaderboard_words(argv: list[str]) -> list[str]:
    """``tcbench leaderboard``'s command line as key=value: the flags ``--experiment``
    (repeatable), ``--sweep``, ``--tracking-uri`` and ``--ecdf`` as its keys, every other word
    as it is."""
    args: list[str] = []
    experiments: list[str] = []
    it = iter(argv)
    for a in it:
        flag, eq, value = a.partition("=")
        if flag in LEADERBOARD_FLAGS:
            if not eq:
                given_value = next(it, None)
                if given_value is None or given_value in HELP_FLAGS:
                    if given_value in HELP_FLAGS:
                        args.append(given_value)
                        continue
                    raise UserError(f"tcbench leaderboard: {flag} needs a value; see `tcbench leaderboard --help`")
                value = given_value
            if flag == "--experiment":
                experiments.append(value)
            else:
                args.append(f"{LEADERBOARD_FLAGS[flag]}={value}")
        elif flag == "--ecdf":
            if eq:
                raise UserError("tcbench leaderboard: --ecdf takes no value (or give ecdf=true)")
            args.append("ecdf=true")
        else:
            args.append(a)
    if len(experiments) == 1:
        args.append(f"experiments={experiments[0]}")
    elif experiments:
        from tcbench.cli.app import hydra_string

        args.append(f"experiments=[{','.join(hydra_string(e) for e in experiments)}]")
    return args


def asks_info(args: list[str]) -> bool:
    """Whether a sweep's command line asks Hydra for information (help, ``--cfg``, ``--info``)
    rather than runs."""
    return any(a in HYDRA_INFO_FLAGS or a.split("=", 1)[0] in HYDRA_INFO_FLAGS for a in args)


def configs_elsewhere(args: list[str]) -> bool:
    """Whether the command line takes its configs from elsewhere (``-cp``, ``-cn``, ``-cd``...)."""
    return any(a in CONFIG_SOURCE_FLAGS for a in args)


def given(args: list[str], key: str) -> bool:
    """Whether the command line sets ``key`` (``hydra.sweep.dir=...``, ``hydra/hydra_logging=...``)."""
    return any(a.split("=", 1)[0].lstrip("+~").removeprefix("override ").strip() == key for a in args)

"""The command registry (:mod:`tcbench.commands.registry`) is the one list of commands: every spec
has its usage, its --help, a schema its primary config starts from and a job kind or an in-process
entry, and ``tcbench --help`` lists exactly the registered commands, in their order."""

from __future__ import annotations

import dataclasses
import inspect

import pytest
import yaml

from tcbench.cli import COMMANDS, main
from tcbench.cli import help as cli_help
from tcbench.cli.main import USAGE
from tcbench.commands.registry import SPECS, CommandSpec, by_config, job_kinds, load
from tcbench.config_dir import conf_dir
from tcbench.runner import kinds


def test_the_usage_lists_exactly_the_registered_commands_in_order(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert out == USAGE + "\n"
    rows = out.split("commands:\n", 1)[1].split("\n\n", 1)[0].splitlines()
    assert [row.split()[0] for row in rows] == list(SPECS) == list(COMMANDS)
    for row, spec in zip(rows, SPECS.values(), strict=True):
        assert row.split(None, 1)[1] == spec.summary


@pytest.mark.parametrize("name", list(SPECS))
def test_every_command_has_usage_help_schema_and_a_kind(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    spec = SPECS[name]
    assert spec.name == name and spec.summary and "\n" not in spec.summary
    assert main([name, "--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: tcbench {name} ") and out.rstrip("\n") == cli_help.usage(name)
    assert "examples:" in out and "output:" in out

    schema = spec.schema_class()
    assert dataclasses.is_dataclass(schema)
    primary = yaml.safe_load((conf_dir() / f"{spec.config}.yaml").read_text(encoding="utf-8"))
    assert spec.schema_node in primary["defaults"]  # the config starts from the schema
    assert by_config(spec.config) is spec
    fields = {f.name: f for f in dataclasses.fields(schema)}
    assert set(spec.inputs) <= set(fields)
    if spec.positional:
        assert spec.positional in fields

    if spec.parser is not None:
        assert callable(load(spec.parser))
    if spec.kinds:
        for kind in spec.kinds:
            job_kind = kinds.kind_of({"kind": kind})
            assert isinstance(job_kind, kinds.JobKind) and job_kind.name == kind
        if "kind" in fields:  # the config names the kind that runs it
            assert fields["kind"].default in spec.kinds
    else:
        module = load(f"{spec.runs_here}:work").__module__
        assert module == spec.runs_here
        for entry in ("check", "work"):
            assert list(inspect.signature(load(f"{spec.runs_here}:{entry}")).parameters) == ["cfg"]


def test_job_kinds_are_unique_to_their_command() -> None:
    every = [kind for spec in SPECS.values() for kind in spec.kinds]
    assert len(every) == len(set(every)) == len(job_kinds())


def test_a_spec_has_job_kinds_or_an_in_process_entry_not_both() -> None:
    with pytest.raises(ValueError, match="one of them"):
        CommandSpec(name="x", summary="x", schema="m:X")
    with pytest.raises(ValueError, match="one of them"):
        CommandSpec(name="x", summary="x", schema="m:X", kinds={"x": "m:XKind"}, runs_here="m")
    spec = CommandSpec(name="x", summary="x", schema="m:X", runs_here="m")
    assert (spec.config, spec.schema_node) == ("x", "x_schema")


def test_every_schema_is_registered_with_hydra() -> None:
    from hydra.core.config_store import ConfigStore

    import tcbench.cli.app  # noqa: F401 - registers the schemas

    stored = set(ConfigStore.instance().list("/"))
    assert {f"{spec.schema_node}.yaml" for spec in SPECS.values()} <= stored


def test_the_repository_hydra_copies_at_each_compose_shares_the_store() -> None:
    """Hydra deep-copies its config repository at every compose; the ConfigStore in it is the
    store itself (not a copy of every schema), so a config registered after the copy is found."""
    import copy

    from hydra import compose, initialize_config_module
    from hydra._internal.config_repository import CachingConfigRepository
    from hydra.core.config_store import ConfigStore
    from hydra.core.global_hydra import GlobalHydra

    import tcbench.cli.app  # noqa: F401 - registers the schemas
    from tcbench.config_dir import CONFIG_MODULE

    store = ConfigStore.instance()
    assert copy.deepcopy(store) is store
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        loader = GlobalHydra.instance().config_loader()
        repo = CachingConfigRepository(loader.repository)  # type: ignore[attr-defined]
        store.store(name="registered_after_the_copy", node={"answer": 42})
        try:
            assert repo.load_config("registered_after_the_copy.yaml") is not None
            node = store.load("registered_after_the_copy.yaml").node
            node.answer = 0  # a loaded node is the caller's copy: the store keeps its own
            assert store.load("registered_after_the_copy.yaml").node.answer == 42
            assert compose("config", overrides=["task=rastrigin", "optimiser=ifa"]).task.name == "rastrigin"
        finally:
            del store.repo["registered_after_the_copy.yaml"]

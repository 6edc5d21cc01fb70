"""``pltf completion bash|zsh``: the shell completion script, generated from pltf's own argument parser.

Rules:
- ``describe`` reads the parser (every command loaded) into plain ``Command``s: options, whether each takes a
  value, and what a value completes to (``Completion``); ``render_bash`` and ``render_zsh`` only print them.
  An option added to any command is completed after the next ``pltf completion``, with no edit here.
- What a value completes to, in this order: the argument's ``choices``; what ``pltf.cli.options.completes`` set
  on it (words, or a function giving them, e.g. the telegram names); FILE or DIR in its metavar; else nothing.
"""

from __future__ import annotations

import argparse
import re
import shlex
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from pltf.cli.options import exit_status

SHELLS = ("bash", "zsh")


@dataclass(frozen=True)
class Completion:
    kind: str  # "none", "file", "dir" or "words"
    words: tuple[str, ...] = ()


NOTHING = Completion("none")


@dataclass(frozen=True)
class Option:
    flags: tuple[str, ...]
    help: str
    value: Completion | None  # None: a flag that takes no value


@dataclass(frozen=True)
class Positional:
    name: str
    help: str
    value: Completion
    optional: bool
    repeated: bool  # nargs * or +: every further word is one of these


@dataclass(frozen=True)
class Command:
    name: str
    help: str
    options: tuple[Option, ...]
    positionals: tuple[Positional, ...]


def _help(action: argparse.Action) -> str:
    return " ".join((action.help or "").replace("%(default)s", str(action.default)).split())


def completion_of(action: argparse.Action) -> Completion:
    """What a value of ``action`` completes to (see the module's rules)."""
    if action.choices is not None:
        return Completion("words", tuple(str(c) for c in action.choices))
    given: str | Iterable[str] | Callable[[], Iterable[str]] | None = getattr(action, "complete", None)
    if callable(given):
        given = given()
    if isinstance(given, str):
        return Completion(given)
    if given is not None:
        return Completion("words", tuple(given))
    metavar = str(action.metavar or "")
    for kind, pattern in (("file", r"\bFILE\b"), ("dir", r"\bDIR\b")):
        if re.search(pattern, metavar):
            return Completion(kind)
    return NOTHING


def _command(name: str, parser: argparse.ArgumentParser, help_text: str) -> Command:
    options, positionals = [], []
    for action in parser._actions:
        if action.help == argparse.SUPPRESS:
            continue
        value = completion_of(action) if action.nargs != 0 else None
        if action.option_strings:
            options.append(Option(tuple(action.option_strings), _help(action), value))
        else:
            positionals.append(
                Positional(
                    action.dest, _help(action), value or NOTHING, action.nargs in ("?", "*"), action.nargs in ("*", "+")
                )
            )
    return Command(name, help_text, tuple(options), tuple(positionals))


def describe(parser: argparse.ArgumentParser) -> tuple[Command, list[Command]]:
    """The top level (its options; its one positional is the command) and every command."""
    top = _command("pltf", parser, parser.description or "")
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {a.dest: a.help or "" for a in sub._choices_actions}
    commands = [_command(name, p, helps.get(name, "")) for name, p in sub.choices.items()]
    return Command(top.name, top.help, top.options, ()), commands


# ---- bash
def _bash_value(value: Completion) -> str:
    if value.kind == "words":
        return f"_pltf_words {shlex.quote(' '.join(value.words))}"
    return {"file": "_pltf_files", "dir": "_pltf_dirs"}.get(value.kind, "COMPREPLY=()")


def _bash_command(cmd: Command) -> list[str]:
    valued = [o for o in cmd.options if o.value is not None]
    flags = " ".join(f for o in cmd.options for f in o.flags)
    out = [
        f"_pltf_{cmd.name.replace('-', '_')}() {{  # {cmd.name}; $1: the index of the word after it",
        "    case $prev in",
    ]
    by_action: dict[str, list[str]] = {}
    for o in valued:
        if o.value is not None:
            by_action.setdefault(_bash_value(o.value), []).extend(o.flags)
    out += [f"        {'|'.join(flags)}) {action}; return ;;" for action, flags in by_action.items()]
    out += [
        "    esac",
        f"    if [[ $cur == -* ]]; then _pltf_words {shlex.quote(flags)}; return; fi",
        "    local n=0 j=$1",
        "    while (( j < cword )); do",
        "        case ${w[j]} in",
    ]
    if valued:
        out.append(f"            {'|'.join(f for o in valued for f in o.flags)}) (( j++ )) ;;")
    out += [
        "            -*) ;;",
        "            *) (( n++ )) ;;",
        "        esac",
        "        (( j++ ))",
        "    done",
        "    case $n in",
    ]
    for i, pos in enumerate(cmd.positionals):
        last = pos.repeated and i == len(cmd.positionals) - 1
        out.append(f"        {'*' if last else i}) {_bash_value(pos.value)} ;;")
    return [*out, "    esac", "}"]


def render_bash(parser: argparse.ArgumentParser) -> str:
    top, commands = describe(parser)
    top_flags = " ".join(f for o in top.options for f in o.flags)
    lines = [
        "# bash completion of pltf, generated from its argument parser by `pltf completion bash`.",
        "# Use: source <(pltf completion bash)   or save it as ~/.local/share/bash-completion/completions/pltf",
        "# The words before the cursor are split at blanks only (COMP_LINE), so a HOST:PORT stays one word.",
        '_pltf_words() { COMPREPLY=($(compgen -W "$1" -- "$cur")); }',
        '_pltf_files() { compopt -o filenames 2>/dev/null; COMPREPLY=($(compgen -f -- "$cur")); }',
        '_pltf_dirs() { compopt -o filenames 2>/dev/null; COMPREPLY=($(compgen -d -- "$cur")); }',
        "_pltf() {",
        "    local line=${COMP_LINE:0:COMP_POINT} cur=${COMP_WORDS[COMP_CWORD]} cmd= i=1",
        "    local -a w; local IFS=$' \\t\\n'",
        '    read -ra w <<< "$line"',
        '    [[ $line == *[[:space:]] || ${#w[@]} -eq 0 ]] && w+=("")',
        "    local cword=$(( ${#w[@]} - 1 ))",
        "    local prev=${w[cword-1]}",
        "    while (( i < cword )); do",
        "        case ${w[i]} in -*) ;; *) cmd=${w[i]}; break ;; esac",
        "        (( i++ ))",
        "    done",
        "    if [[ -z $cmd ]]; then",
        f"        if [[ $cur == -* ]]; then _pltf_words {shlex.quote(top_flags)};",
        f"        else _pltf_words {shlex.quote(' '.join(c.name for c in commands))}; fi",
        "        return 0",
        "    fi",
        "    local func=_pltf_${cmd//-/_}",
        '    if declare -F "$func" >/dev/null; then "$func" $((i + 1)); fi',
        "    return 0",
        "}",
    ]
    for cmd in commands:
        lines += _bash_command(cmd)
    return "\n".join([*lines, "complete -F _pltf pltf", ""])


# ---- zsh
def _zsh_quote(text: str) -> str:
    return "'" + text.replace("'", "'\\''") + "'"


def _zsh_text(text: str) -> str:
    return text.replace("[", "(").replace("]", ")").replace(":", "\\:")


def _zsh_action(value: Completion) -> str:
    if value.kind == "words":
        return "(" + " ".join(value.words) + ")"
    return {"file": "_files", "dir": "_path_files -/"}.get(value.kind, " ")


def _zsh_specs(cmd: Command) -> list[str]:
    specs = []
    for o in cmd.options:
        for flag in o.flags:
            if o.value is None:
                specs.append(f"{flag}[{_zsh_text(o.help)}]")
            else:
                specs.append(
                    f"{flag}=[{_zsh_text(o.help)}]:{_zsh_text(o.flags[-1].lstrip('-'))}:{_zsh_action(o.value)}"
                )
    for i, pos in enumerate(cmd.positionals, 1):
        where = "*" if pos.repeated else str(i)
        optional = ":" if pos.optional and not pos.repeated else ""
        specs.append(f"{where}:{optional}{_zsh_text(pos.name)}:{_zsh_action(pos.value)}")
    return specs


def render_zsh(parser: argparse.ArgumentParser) -> str:
    top, commands = describe(parser)
    lines = [
        "#compdef pltf",
        "# zsh completion of pltf, generated from its argument parser by `pltf completion zsh`.",
        "# Use: source <(pltf completion zsh)   or save it as _pltf in a directory of $fpath",
        "_pltf() {",
        "    local curcontext=$curcontext state line ret=1",
        "    typeset -A opt_args",
        "    _arguments -C "
        + " ".join(_zsh_quote(s) for s in _zsh_specs(top))
        + " '1: :->command' '*:: :->args' && ret=0",
        "    case $state in",
        "        command)",
        "            local -a commands=(" + " ".join(_zsh_quote(f"{c.name}:{c.help}") for c in commands) + ")",
        "            _describe -t commands 'pltf command' commands && ret=0 ;;",
        "        args)",
        "            curcontext=${curcontext%:*:*}:pltf-$words[1]:",
        "            case $words[1] in",
    ]
    for cmd in commands:
        lines.append(
            f"                {cmd.name}) _arguments "
            + " ".join(_zsh_quote(s) for s in _zsh_specs(cmd))
            + " && ret=0 ;;"
        )
    lines += [
        "            esac ;;",
        "    esac",
        "    return ret",
        "}",
        'if [[ $zsh_eval_context[-1] == loadautofunc ]]; then _pltf "$@"; else compdef _pltf pltf; fi',
        "",
    ]
    return "\n".join(lines)


RENDER = {"bash": render_bash, "zsh": render_zsh}


def add_completion_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("shell", choices=SHELLS, help="the shell the script is for")
    p.epilog = exit_status(
        ok="the script is on stdout (bash: source <(pltf completion bash); zsh: the same, or "
        "save it as _pltf in a directory of $fpath)",
        usage="usage error: an unknown shell",
    )


def run_completion(args: argparse.Namespace) -> int:
    from pltf.cli.main import COMMANDS, make_parser

    sys.stdout.write(RENDER[args.shell](make_parser(load=COMMANDS)))
    return 0

"""``pltf decode`` and ``pltf encode``: the codec on the command line.

They import the codec and nothing else of the toolkit (issue 18: they start in <= 0.3 s).
"""

from __future__ import annotations

import argparse
import json
import sys

from pltf.cli.options import CommandError, completes, exit_status
from pltf.spec import errors
from pltf.spec.codec import TelegramDecoder, encode
from pltf.spec.jsonio import fields_to_telegram, telegram_to_json


def add_decode_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("hex", help="frames as hex (spaces allowed), or - to read hex from stdin")
    p.add_argument("--reply", action="store_true", help="decode reply telegrams (default: requests)")
    p.epilog = exit_status(
        ok="every frame decoded (one JSON object per telegram on stdout)",
        usage="usage error: not hex, no frame, a malformed frame or an unknown telegram id",
    )


def run_decode(args: argparse.Namespace) -> int:
    text = sys.stdin.read() if args.hex == "-" else args.hex
    try:
        data = bytes.fromhex("".join(text.split()))
    except ValueError as exc:
        raise CommandError(f"not hex: {exc}") from None
    dec = TelegramDecoder("reply" if args.reply else "request")
    dec.receive_data(data)
    dec.receive_data(b"")
    try:
        count = 0
        for telegram in dec:
            print(json.dumps(telegram_to_json(telegram)))
            count += 1
    except errors.RemoteProtocolError as exc:
        raise CommandError(f"{type(exc).__name__}: {exc}") from None
    if count == 0:
        raise CommandError("no telegram in the input")
    return 0


def _telegram_names() -> list[str]:
    from pltf.spec.model import load_telegrams

    return [name for t in load_telegrams() for name in (t.name, *t.aliases)]


def add_encode_arguments(p: argparse.ArgumentParser) -> None:
    name = p.add_argument("name", help="telegram name as in the guide, e.g. CMD_SET_MODE")
    completes(name, _telegram_names)
    p.add_argument("fields", nargs="?", default="{}", help="the fields object as JSON (as decode prints it)")
    p.add_argument("--reply", action="store_true", help="encode a reply telegram (default: request)")
    p.epilog = exit_status(
        ok="encoded (the frame as hex on stdout)",
        usage="usage error: unknown telegram, fields not JSON, a field missing, unknown or out of range",
    )


def run_encode(args: argparse.Namespace) -> int:
    try:
        fields = json.loads(args.fields)
    except json.JSONDecodeError as exc:
        raise CommandError(f"fields are not JSON: {exc}") from None
    try:
        telegram = fields_to_telegram("reply" if args.reply else "request", args.name, fields)
        print(encode(telegram).hex())
    except errors.ProtocolError as exc:
        raise CommandError(str(exc)) from None
    except TypeError as exc:
        raise CommandError(f"{args.name}: {exc}") from None
    return 0

"""``pltf decode`` and ``pltf encode``: the codec on the command line."""

from __future__ import annotations

import argparse
import json
import sys

from pltf.spec import errors
from pltf.spec.codec import TelegramDecoder, encode
from pltf.spec.jsonio import fields_to_telegram, telegram_to_json


def _fail(message: str) -> int:
    print(f"pltf: error: {message}", file=sys.stderr)
    return 2


def add_decode_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("hex", help="frames as hex (spaces allowed), or - to read hex from stdin")
    p.add_argument("--reply", action="store_true", help="decode reply telegrams (default: requests)")


def run_decode(args: argparse.Namespace) -> int:
    text = sys.stdin.read() if args.hex == "-" else args.hex
    try:
        data = bytes.fromhex("".join(text.split()))
    except ValueError as exc:
        return _fail(f"not hex: {exc}")
    dec = TelegramDecoder("reply" if args.reply else "request")
    dec.receive_data(data)
    dec.receive_data(b"")
    try:
        count = 0
        for telegram in dec:
            print(json.dumps(telegram_to_json(telegram)))
            count += 1
    except errors.RemoteProtocolError as exc:
        return _fail(f"{type(exc).__name__}: {exc}")
    if count == 0:
        return _fail("no telegram in the input")
    return 0


def add_encode_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", help="telegram name as in the guide, e.g. CMD_SET_MODE")
    p.add_argument("fields", nargs="?", default="{}", help="the fields object as JSON (as decode prints it)")
    p.add_argument("--reply", action="store_true", help="encode a reply telegram (default: request)")


def run_encode(args: argparse.Namespace) -> int:
    try:
        fields = json.loads(args.fields)
    except json.JSONDecodeError as exc:
        return _fail(f"fields are not JSON: {exc}")
    try:
        telegram = fields_to_telegram("reply" if args.reply else "request", args.name, fields)
        print(encode(telegram).hex())
    except errors.ProtocolError as exc:
        return _fail(str(exc))
    except TypeError as exc:
        return _fail(f"{args.name}: {exc}")
    return 0

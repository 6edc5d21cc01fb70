"""The doc-test markers of the tutorial pages (tests/docs/blocks.py): parsed as written, refused when wrong."""

from __future__ import annotations

import pytest

from tests.docs.blocks import localize, parse

PAGE = """# t

<!-- doc-test background until="server started at port" count=2 -->
```sh
pltf serve --ports 10000,10002
```

```sh
untested
```

<!-- doc-test slow exit=1 expect="FAIL x" -->
```sh
pltf conform --target 127.0.0.1:10000 --second-port 10002
```

<!-- doc-test file=hello.py -->
```python
print("y_mm=10000")
```
"""


def test_markers_are_read_as_written() -> None:
    serve, conform, hello = parse(PAGE, "t.md")
    assert serve.background and serve.until == "server started at port" and serve.count == 2 and serve.line == 4
    assert conform.slow and conform.exit == 1 and conform.expect == "FAIL x" and not conform.background
    assert hello.file == "hello.py" and hello.lang == "python" and hello.code == 'print("y_mm=10000")\n'


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("<!-- doc-test -->\ntext\n", "must be right above a fenced block"),
        ("<!-- doc-test -->\n```sh\nx\n", "not closed"),
        ("<!-- doc-test retries=3 -->\n```sh\nx\n```\n", "unknown doc-test option"),
    ],
)
def test_a_wrong_marker_is_refused(text: str, why: str) -> None:
    with pytest.raises(ValueError, match=why):
        parse(text, "t.md")


def test_well_known_ports_become_free_ones() -> None:
    ports = {10000: 40000, 10002: 40002, 10010: 40004, 10012: 40006, 8080: 40008}
    assert localize("--target 127.0.0.1:10000 --second-port 10002 x100000", ports) == (
        "--target 127.0.0.1:40000 --second-port 40002 x100000"
    )

"""``POST /api/validate?kind=map|roadmap``: the editors' check before sending (issue 20).

The browser has no XSD validator; the gateway runs the project's own (spec/documents.py ``validate_document``,
the XSDs in spec/schemas) on the document the editor is about to send. The answer is JSON: ``{"ok": true}``, or
``{"ok": false, "message": ONE LINE, "line": N or null}`` for a document that must not be sent (the editor points
at the object on that line). Any bytes get an answer, never a traceback; a request from another origin never gets
here (doors.py).
"""

from __future__ import annotations

from aiohttp import web

from pltf.spec.documents import DocumentError, DocumentKind, validate_document

KINDS = {"map": DocumentKind.MAP, "roadmap": DocumentKind.ROADMAP}
MAX_BODY = 16 * 1024 * 1024


async def validate(request: web.Request) -> web.Response:
    kind = KINDS.get(request.query.get("kind", ""))
    if kind is None:
        raise web.HTTPBadRequest(text=f"kind must be one of {', '.join(KINDS)}")
    data = bytearray()
    async for chunk in request.content.iter_chunked(1 << 16):  # past aiohttp's 1 MB limit of request.read()
        data += chunk
        if len(data) > MAX_BODY:
            return web.json_response({"ok": False, "message": f"the document is over {MAX_BODY} bytes", "line": None})
    try:
        validate_document(kind, bytes(data), max_size=MAX_BODY)
    except DocumentError as exc:
        return web.json_response({"ok": False, "message": str(exc), "line": exc.line})
    return web.json_response({"ok": True})


def add_routes(app: web.Application) -> None:
    app.router.add_post("/api/validate", validate)

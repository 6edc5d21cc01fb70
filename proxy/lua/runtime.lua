-- The dissector itself: it reads the tables above (TELEGRAMS, ENUMS, generated from spec/) and never names a
-- telegram. Rules, after spec/codec.py:
-- * Framing (guide 6.2): header FF 01 FE 02, a big-endian uint32 N counting the data bytes, then N data bytes
--   whose first byte is the telegram identifier; replies are framed like requests (erratum E-WIRE-001).
--   Telegrams split across TCP segments are reassembled; several in one segment are dissected one by one.
-- * Direction: bytes sent to the port the dissector was registered on (or chosen with Decode As) are requests,
--   bytes from it replies.
-- * A telegram is checked as the codec checks it (its layout, enums, ranges, constants, lengths and counts) and
--   every problem is an expert info named after the codec's error class; a frame that does not decode is shown
--   as far as it goes and marked, never decoded as something else.
-- * A framing error (bad header, length over the maximum) loses the frame boundaries of that direction: the
--   bytes after it are marked "out of sync" and not decoded (no guessing at the next header).
-- * Values as `pltf decode` prints them: integers as numbers (enums with their names), doubles in the shortest
--   form that reads back exactly, strings JSON-escaped (every byte of a Latin-1 string, NUL included, visible).

local WIRE_SIZE = { BYTE = 1, BOOL = 1, INT16 = 2, INT = 4, DOUBLE = 8 }
local BOOL_NAMES = { [0] = "false", [1] = "true" }
local DESEGMENT_MORE = DESEGMENT_ONE_MORE_SEGMENT

local pltf = Proto("pltf", "Neobotix PlatformCtrl")

-- ------------------------------------------------------------------------------------------- fields
local F = {
  header = ProtoField.bytes("pltf.header", "Header", base.SPACE, "FF 01 FE 02 (guide 6.2)"),
  length = ProtoField.uint32("pltf.length", "Length", base.DEC, nil, nil, "Data bytes after the length field"),
  name = ProtoField.string("pltf.telegram", "Telegram", base.ASCII, "Telegram name (guide 6.3, 6.4)"),
  error = ProtoField.string("pltf.error", "Error", base.ASCII, "Why the bytes do not decode (codec error class)"),
  data = ProtoField.bytes("pltf.data", "Data", base.NONE, "Bytes that do not decode"),
  trailing = ProtoField.bytes("pltf.trailing", "Trailing bytes", base.NONE, "Bytes after the last field"),
}
local ID_NAMES = { request = {}, reply = {} }
for dir, set in pairs(TELEGRAMS) do
  for id, t in pairs(set) do ID_NAMES[dir][id] = t.name end
end
F.request = ProtoField.uint8("pltf.request", "Request", base.DEC, ID_NAMES.request, nil, "Telegram identifier (request)")
F.reply = ProtoField.uint8("pltf.reply", "Reply", base.DEC, ID_NAMES.reply, nil, "Telegram identifier (reply)")

local EXPERT = {}
for _, e in ipairs({
  { "BadHeader", "bad_header", "The frame does not start with FF 01 FE 02 (guide 6.2)" },
  { "FrameTooLarge", "frame_too_large", "The length field is over the maximum (erratum E-WIRE-004)" },
  { "Truncated", "truncated", "The telegram is shorter than its layout" },
  { "TrailingBytes", "trailing_bytes", "Bytes after the last field of the telegram" },
  { "UnknownTelegram", "unknown_telegram", "The identifier is not a telegram of this direction" },
  { "FieldOutOfRange", "field_out_of_range", "A value outside its enum, range or constant" },
  { "LengthMismatch", "length_mismatch", "A string length or count disagrees with the bytes that follow" },
  { "OutOfSync", "out_of_sync", "After a framing error the frame boundaries are lost" },
}) do
  EXPERT[e[1]] = ProtoExpert.new("pltf." .. e[2], e[1] .. ": " .. e[3], expert.group.MALFORMED, expert.severity.ERROR)
end

local function blurb(f)
  local unit = f.unit and (", " .. f.unit) or ""
  return f.type .. (f.rep and ("[" .. f.rep .. "]") or "") .. unit .. ": " .. f.desc
end

-- A ProtoField per field of the spec, with the sizes and the runs of fixed-size fields the codec uses.
local function prepare(layout)
  local steps, run = {}, nil
  for _, f in ipairs(layout) do
    local names = f.enum and ENUMS[f.enum] or (f.type == "BOOL" and BOOL_NAMES or nil)
    f.names = names
    if f.type == "BYTE" or f.type == "BOOL" then
      f.pf = ProtoField.uint8(f.abbr, f.name, base.DEC, names, nil, blurb(f))
    elseif f.type == "INT16" then
      f.pf = ProtoField.int16(f.abbr, f.name, base.DEC, names, nil, blurb(f))
    elseif f.type == "INT" then
      f.pf = ProtoField.int32(f.abbr, f.name, base.DEC, names, nil, blurb(f))
    elseif f.type == "DOUBLE" then
      f.pf = ProtoField.double(f.abbr, f.name, blurb(f))
    elseif f.type == "GROUP" then
      f.pf_count = ProtoField.int32(f.abbr .. "_count", f.name .. " count", base.DEC, nil, nil, "INT: number of " .. f.item)
      prepare(f.fields)
      f.item_min = 0
      for _, g in ipairs(f.fields) do f.item_min = f.item_min + (g.size or 4) end
    else -- STRING, XML
      f.pf = ProtoField.string(f.abbr, f.name, base.UNICODE, blurb(f))
      f.pf_length = ProtoField.int32(f.abbr .. "_length", f.name .. " length", base.DEC, nil, nil, "INT: bytes")
    end
    local size = WIRE_SIZE[f.type]
    if size then
      f.size = size * (f.rep or 1)
      if not run then run = { fields = {}, size = 0 }; table.insert(steps, run) end
      table.insert(run.fields, f)
      run.size = run.size + f.size
    else
      run = nil
      table.insert(steps, { var = f })
    end
  end
  layout.steps = steps
end

local function register(layout, list)
  for _, f in ipairs(layout) do
    for _, k in ipairs({ "pf", "pf_count", "pf_length" }) do
      if f[k] then table.insert(list, f[k]) end
    end
    if f.fields then register(f.fields, list) end
  end
end

local all_fields = {}
for _, pf in pairs(F) do table.insert(all_fields, pf) end
for _, set in pairs(TELEGRAMS) do
  for _, t in pairs(set) do
    if t.layout then
      prepare(t.layout)
      register(t.layout, all_fields)
    else
      t.pf_payload = ProtoField.bytes(t.abbr .. ".payload", "payload", base.NONE, "OPAQUE: every byte after the identifier (layout unknown)")
      table.insert(all_fields, t.pf_payload)
    end
  end
end
pltf.fields = all_fields
local experts = {}
for _, e in pairs(EXPERT) do table.insert(experts, e) end
pltf.experts = experts

-- ------------------------------------------------------------------------------------------- values
local function repr(v)
  if v ~= v then return "nan" end
  if v == math.huge then return "inf" end
  if v == -math.huge then return "-inf" end
  for p = 1, 17 do
    local s = string.format("%." .. p .. "g", v)
    if tonumber(s) == v then return s end
  end
  return string.format("%.17g", v)
end

local ESCAPES = { [34] = '\\"', [92] = "\\\\", [8] = "\\b", [9] = "\\t", [10] = "\\n", [12] = "\\f", [13] = "\\r" }

-- Latin-1 bytes as JSON string content (without the quotes), UTF-8 encoded: what json.dumps(s,
-- ensure_ascii=False) writes between the quotes.
local function latin1_json(raw)
  local out = {}
  for i = 1, #raw do
    local b = raw:byte(i)
    if ESCAPES[b] then
      out[#out + 1] = ESCAPES[b]
    elseif b < 32 or b == 127 then
      out[#out + 1] = string.format("\\u%04x", b)
    elseif b < 128 then
      out[#out + 1] = string.char(b)
    elseif b < 160 then
      out[#out + 1] = string.format("\\u%04x", b) -- C1 controls: escaped like the other controls
    else
      out[#out + 1] = string.char(0xC0 + math.floor(b / 64), 0x80 + b % 64)
    end
  end
  return table.concat(out)
end

-- ------------------------------------------------------------------------------------------- one telegram
local function problem(ctx, tree, kind, message)
  table.insert(ctx.errors, kind)
  tree:add_proto_expert_info(EXPERT[kind], kind .. ": " .. message)
end

local function scalar(buf, pos, f, tree, ctx, where)
  local size = WIRE_SIZE[f.type]
  local range = buf(pos, size)
  local v
  if f.type == "DOUBLE" then
    v = range:float()
    local item = tree:add(f.pf, range)
    item:set_text(f.name .. ": " .. repr(v) .. (f.unit and (" " .. f.unit) or ""))
    return pos + size, v
  elseif f.type == "BYTE" or f.type == "BOOL" then
    v = range:uint()
  else
    v = range:int()
  end
  local item = tree:add(f.pf, range)
  if f.unit then item:append_text(" " .. f.unit) end
  if f.const ~= nil then
    if v ~= f.const then
      problem(ctx, item, "FieldOutOfRange", string.format("%s.%s: %d, the guide fixes it at %d", where, f.name, v, f.const))
    end
  elseif f.names and f.names[v] == nil then
    problem(ctx, item, "FieldOutOfRange", string.format("%s.%s: %d is not a valid %s value", where, f.name, v, f.enum or f.type))
  elseif (f.min and v < f.min) or (f.max and v > f.max) then
    problem(ctx, item, "FieldOutOfRange", string.format("%s.%s: %d outside %.0f..%.0f", where, f.name, v,
      f.min or -2 ^ 63, f.max or 2 ^ 63))
  end
  return pos + size, v
end

local dissect_layout

local function variable(buf, pos, stop, f, tree, ctx, where)
  if stop - pos < 4 then
    problem(ctx, tree, "Truncated", string.format("%s: telegram of %d bytes is shorter than its layout", ctx.name, ctx.size))
    return nil
  end
  local n = buf(pos, 4):int()
  local left = stop - pos - 4
  if f.type == "GROUP" then
    local sub = tree:add(buf(pos, math.min(stop - pos, 4 + math.max(n, 0) * f.item_min)),
      string.format("%s: %d %s", f.name, n, f.item))
    sub:add(f.pf_count, buf(pos, 4))
    if n < 0 or n * f.item_min > left then
      problem(ctx, sub, "LengthMismatch", string.format("%s.%s: count %d but only %d bytes remain", where, f.name, n, left))
      return nil
    end
    pos = pos + 4
    local start = pos
    for i = 1, n do
      local item = sub:add(buf(pos, f.item_min), string.format("%s #%d", f.item, i))
      local after = dissect_layout(buf, pos, stop, f.fields, item, ctx, where .. "." .. f.name .. "[]")
      if not after then return nil end
      if after > pos then item:set_len(after - pos) end
      pos = after
    end
    if pos > start then sub:set_len(pos - start + 4) end
    return pos
  end
  local item_len = tree:add(f.pf_length, buf(pos, 4))
  if n < 0 or n > left then
    problem(ctx, item_len, "LengthMismatch", string.format("%s.%s: length %d but only %d bytes remain", where, f.name, n, left))
    return nil
  end
  pos = pos + 4
  if n == 0 then
    tree:add(f.pf, buf(pos - 4, 4), "")
  else
    tree:add(f.pf, buf(pos, n), latin1_json(buf(pos, n):raw()))
  end
  return pos + n
end

dissect_layout = function(buf, pos, stop, layout, tree, ctx, where)
  for _, step in ipairs(layout.steps) do
    if step.var then
      pos = variable(buf, pos, stop, step.var, tree, ctx, where)
      if not pos then return nil end
    else
      if stop - pos < step.size then
        problem(ctx, tree, "Truncated", string.format("%s: telegram of %d bytes is shorter than its layout", ctx.name, ctx.size))
        return nil
      end
      for _, f in ipairs(step.fields) do
        if f.rep then
          local sub = tree:add(buf(pos, f.size), string.format("%s: %d x %s", f.name, f.rep, f.type))
          for _ = 1, f.rep do pos = scalar(buf, pos, f, sub, ctx, where) end
        else
          pos = scalar(buf, pos, f, tree, ctx, where)
        end
      end
    end
  end
  return pos
end

-- One whole frame (header, length, data) of `size` data bytes at `base` of `tvb`; returns the telegram's name
-- and its first error class.
local function dissect_frame(tvb, base, size, tree, direction)
  local t = tree:add(pltf, tvb(base, 8 + size))
  t:add(F.header, tvb(base, 4))
  t:add(F.length, tvb(base + 4, 4))
  local ctx = { errors = {}, size = size, name = "?" }
  if size == 0 then
    problem(ctx, t, "UnknownTelegram", "empty telegram: no identifier byte")
    t:set_text("PlatformCtrl " .. direction .. ": empty frame [UnknownTelegram]")
    return "empty frame", "UnknownTelegram"
  end
  local id_range = tvb(base + 8, 1)
  local id = id_range:uint()
  t:add(F[direction], id_range)
  local tdef = TELEGRAMS[direction][id]
  if not tdef then
    problem(ctx, t, "UnknownTelegram", string.format("unknown %s identifier %d", direction, id))
    if size > 1 then t:add(F.data, tvb(base + 9, size - 1)) end
    t:set_text(string.format("PlatformCtrl %s: unknown identifier %d [UnknownTelegram]", direction, id))
    return "unknown " .. id, "UnknownTelegram"
  end
  ctx.name = tdef.name
  t:add(F.name, id_range, tdef.name):set_generated()
  local stop = base + 8 + size
  if not tdef.layout then
    if size > 1 then
      t:add(tdef.pf_payload, tvb(base + 9, size - 1))
    else
      t:add(tdef.pf_payload, tvb(base + 9, 0)):set_text("payload: (none)")
    end
  else
    local pos = dissect_layout(tvb, base + 9, stop, tdef.layout, t, ctx, tdef.name)
    if pos and pos < stop then
      t:add(F.trailing, tvb(pos, stop - pos))
      problem(ctx, t, "TrailingBytes", string.format("%s: %d bytes after the last field", tdef.name, stop - pos))
    end
  end
  local first = ctx.errors[1]
  local label = string.format("PlatformCtrl %s: %s (%s)", direction, tdef.name, tdef.section)
  if first then
    t:add(F.error, id_range, first):set_generated()
    label = label .. " [" .. first .. "]"
  end
  t:set_text(label)
  return tdef.name, first
end

-- ------------------------------------------------------------------------------------------- the stream
local tcp_stream = Field.new("tcp.stream")
local out_of_sync = {} -- "<tcp stream>/<direction>" -> frame number of the framing error

function pltf.init()
  out_of_sync = {}
  heur_server = {}
end

local HEADER_BYTES = { 0xFF, 0x01, 0xFE, 0x02 }

local function header_ok(tvb, offset, avail)
  for i = 1, math.min(4, avail) do
    if tvb(offset + i - 1, 1):uint() ~= HEADER_BYTES[i] then return false end
  end
  return true
end

-- Streams found by the heuristic (any port): "<tcp stream>" -> the server's port, the destination of the stream's
-- first PlatformCtrl bytes. Guide 6.1: "This interface accepts commands and returns data only on request." The
-- platform never speaks first, so the side that sends the first frame is the client (a capture that starts
-- after a request may show a reply first: then that stream's directions are swapped, see proxy/README.md).
local heur_server = {}

local function direction_of(pinfo, stream)
  local server = stream and heur_server[stream]
  if server then
    return pinfo.dst_port == server and "request" or "reply"
  end
  local port = pinfo.match_uint
  if port == nil or port == 0 then
    return PORTS[pinfo.dst_port] and "request" or "reply"
  end
  return pinfo.dst_port == port and "request" or "reply"
end

local function summary(pinfo, direction, names)
  local arrow = direction == "request" and "request" or "reply"
  pinfo.cols.protocol = "PLTF"
  local text, last, count = {}, nil, 0
  local function flush()
    if last then table.insert(text, count > 1 and string.format("%s (x%d)", last, count) or last) end
  end
  for _, n in ipairs(names) do
    if n == last then count = count + 1 else flush(); last, count = n, 1 end
  end
  flush()
  pinfo.cols.info:set(arrow .. ": " .. table.concat(text, ", "))
end

function pltf.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  if len == 0 then return 0 end
  local stream = tcp_stream()
  stream = stream and tostring(stream.value)
  local direction = direction_of(pinfo, stream)
  local key = (stream or "?") .. "/" .. direction
  local lost = out_of_sync[key]
  if lost and pinfo.number > lost then
    local t = tree:add(pltf, tvb(), "PlatformCtrl " .. direction .. ": out of sync")
    t:add(F.data, tvb())
    t:add_proto_expert_info(EXPERT.OutOfSync, "OutOfSync: after the framing error in frame " .. lost)
    summary(pinfo, direction, { "[OutOfSync]" })
    return len
  end
  local names = {}
  local offset = 0
  while offset < len do
    local avail = len - offset
    local bad, message
    if not header_ok(tvb, offset, avail) then
      bad = "BadHeader"
      message = "bad header " .. tostring(tvb(offset, math.min(4, avail)):bytes()):lower() .. " (expected ff01fe02)"
    elseif avail < 8 then
      pinfo.desegment_offset = offset
      pinfo.desegment_len = DESEGMENT_MORE
      break
    else
      local n = tvb(offset + 4, 4):uint()
      if n > MAX_LENGTH then
        bad = "FrameTooLarge"
        message = string.format("frame length %d over the maximum %d", n, MAX_LENGTH)
      elseif avail < 8 + n then
        pinfo.desegment_offset = offset
        pinfo.desegment_len = 8 + n - avail
        break
      else
        local name, err = dissect_frame(tvb, offset, n, tree, direction)
        table.insert(names, err and (name .. " [" .. err .. "]") or name)
        offset = offset + 8 + n
      end
    end
    if bad then
      if not lost or pinfo.number < lost then out_of_sync[key] = pinfo.number end
      local t = tree:add(pltf, tvb(offset), "PlatformCtrl " .. direction .. ": malformed [" .. bad .. "]")
      t:add(F.data, tvb(offset))
      t:add(F.error, tvb(offset, math.min(4, avail)), bad):set_generated()
      t:add_proto_expert_info(EXPERT[bad], bad .. ": " .. message)
      table.insert(names, "[" .. bad .. "]")
      break
    end
  end
  if #names > 0 then summary(pinfo, direction, names) end
  return len
end

-- ------------------------------------------------------------------------------------------- any port
-- A heuristic dissector on TCP: a stream whose bytes start with the header FF 01 FE 02 and a sane length (at
-- least the identifier byte, at most MAX_LENGTH; guide 6.2) is PlatformCtrl on whatever port it runs, in both
-- directions. Wireshark tries it on TCP payload no port-registered dissector took; once it says yes, the whole
-- conversation is ours (pinfo.conversation), so the segments after it, replies included, come here directly.
local function heuristic(tvb, pinfo, tree)
  local len = tvb:len()
  if len < 8 or not header_ok(tvb, 0, 4) then return false end
  local n = tvb(4, 4):uint()
  if n < 1 or n > MAX_LENGTH then return false end
  local stream = tcp_stream()
  if stream and not pinfo.visited then
    local key = tostring(stream.value)
    if heur_server[key] == nil then heur_server[key] = pinfo.dst_port end
  end
  pinfo.conversation = pltf
  pltf.dissector(tvb, pinfo, tree)
  return true
end

local tcp_table = DissectorTable.get("tcp.port")
for port in pairs(PORTS) do tcp_table:add(port, pltf) end
tcp_table:add_for_decode_as(pltf)
pltf:register_heuristic("tcp", heuristic)

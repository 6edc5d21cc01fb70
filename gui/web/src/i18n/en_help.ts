/** English labels of the keyboard help overlay and the toolbar tooltips (issue 35). */
export const enHelp = {
  "help.open": "Keyboard shortcuts (?)",
  "help.title": "Keyboard shortcuts",
  "help.close": "Close",
  "help.keys": "Keys",
  "help.what": "What it does",
  "help.where": "Where",
  "help.hint": "Press ? to show this list, Escape to close it.",
  // the keys' names
  "help.key.ctrl": "Ctrl",
  "help.key.alt": "Alt",
  "help.key.shift": "Shift",
  "help.key.escape": "Escape",
  "help.key.enter": "Enter",
  "help.key.arrows": "Arrow keys",
  "help.key.wheel": "Mouse wheel",
  "help.or": "or",
  // where a shortcut works
  "help.where.anywhere": "Anywhere",
  "help.where.map": "Map (focused)",
  "help.where.mapPointer": "Map (under the pointer)",
  "help.where.drive": "Motion modes Velocity, Joystick (Software)",
  "help.where.open": "Menus, dialogs, this list",
  // what it does: the guide's words (quoted from the section named)
  "help.do.help": "Show this list of keyboard shortcuts",
  "help.do.close": "Close this list, an open menu or a dialog",
  "help.do.openSocket": "Open Socket: the GUI connects to the last connected PlatformControl (guide 5.2)",
  "help.do.init":
    "Init: an initialization of the CAN-field bus (CMD_CONNECT_TO_PLTF), then initializes all CAN-hardware components and executes a platform self test (CMD_INIT_PLTF)",
  "help.do.start":
    'Start: start a platform motion mode; the operation state changes into the state "Moving" (CMD_START)',
  "help.do.break":
    'Break: break a platform motion mode; the operation state changes into the state "Break" (CMD_BREAK)',
  "help.do.continue":
    'Continue: continue the execution of a platform motion mode; the operation state changes into the state "Moving" (CMD_CONTINUE)',
  "help.do.stop":
    'Stop: stop the motion of the platform; the operation state changes into the state "Ready" (CMD_STOP)',
  "help.do.drive":
    "Drive while held: the desired translation and rotation velocities are set to the platform using the command CMD_MOVE_VEL (guide 4.3); releasing stops",
  "help.do.pan": "Pan: scroll the map (guide 5.3)",
  "help.do.zoom": "Zoom in, zoom out (guide 5.3), at the pointer",
} as const;

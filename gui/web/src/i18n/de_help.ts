/** German labels of the keyboard help overlay and the toolbar tooltips (issue 35). */
import type { enHelp } from "./en_help";

export const deHelp: Record<keyof typeof enHelp, string> = {
  "help.open": "Tastenkürzel (?)",
  "help.title": "Tastenkürzel",
  "help.close": "Schließen",
  "help.keys": "Tasten",
  "help.what": "Was sie tun",
  "help.where": "Wo",
  "help.hint": "? zeigt diese Liste, Escape schließt sie.",
  "help.key.ctrl": "Strg",
  "help.key.alt": "Alt",
  "help.key.shift": "Umschalt",
  "help.key.escape": "Esc",
  "help.key.enter": "Eingabe",
  "help.key.arrows": "Pfeiltasten",
  "help.key.wheel": "Mausrad",
  "help.or": "oder",
  "help.where.anywhere": "Überall",
  "help.where.map": "Karte (mit Fokus)",
  "help.where.mapPointer": "Karte (unter dem Mauszeiger)",
  "help.where.drive": "Bewegungsmodi Velocity, Joystick (Software)",
  "help.where.open": "Menüs, Dialoge, diese Liste",
  "help.do.help": "Diese Liste der Tastenkürzel zeigen",
  "help.do.close": "Diese Liste, ein offenes Menü oder einen Dialog schließen",
  "help.do.openSocket":
    "Open Socket: die GUI verbindet sich mit der zuletzt verbundenen PlatformControl (Handbuch 5.2)",
  "help.do.init":
    "Init: initialisiert den CAN-Feldbus (CMD_CONNECT_TO_PLTF), dann alle CAN-Hardwarekomponenten und führt einen Selbsttest der Plattform aus (CMD_INIT_PLTF)",
  "help.do.start": 'Start: startet einen Bewegungsmodus; der Betriebszustand wechselt in "Moving" (CMD_START)',
  "help.do.break": 'Break: unterbricht einen Bewegungsmodus; der Betriebszustand wechselt in "Break" (CMD_BREAK)',
  "help.do.continue":
    'Continue: setzt einen Bewegungsmodus fort; der Betriebszustand wechselt in "Moving" (CMD_CONTINUE)',
  "help.do.stop": 'Stop: hält die Bewegung der Plattform an; der Betriebszustand wechselt in "Ready" (CMD_STOP)',
  "help.do.drive":
    "Fahren, solange gedrückt: die gewünschte Translations- und Rotationsgeschwindigkeit wird mit CMD_MOVE_VEL an die Plattform gesendet (Handbuch 4.3); Loslassen hält an",
  "help.do.pan": "Verschieben: die Karte scrollen (Handbuch 5.3)",
  "help.do.zoom": "Vergrößern, verkleinern (Handbuch 5.3), am Mauszeiger",
};

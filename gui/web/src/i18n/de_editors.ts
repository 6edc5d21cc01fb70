/** German labels of the editors' tools added by issue 20's second part. */
import type { enEditors } from "./en_editors";

export const deEditors: Record<keyof typeof enEditors, string> = {
  "edit.active": "Karte an die Plattform gesendet und aktiv (CMD_GET_MAP liefert sie): {n} Objekte",
  "edit.notTaken":
    "Die Plattform hat die Karte nicht übernommen: CMD_GET_MAP nach CMD_SET_MAP liefert eine andere Karte (CMD_SET_MAP hat keine Antwort mit einem Grund)",
  "rm.active":
    "Straßenkarte an die Plattform gesendet und aktiv (CMD_GET_ROADMAP liefert sie): {n} Stationen, {e} Kanten",
  "rm.notTaken":
    "Die Plattform hat die Straßenkarte nicht übernommen: CMD_GET_ROADMAP nach CMD_SET_ROADMAP liefert eine andere (CMD_SET_ROADMAP hat keine Antwort mit einem Grund)",
  "edit.saveAs": "Speichern unter",
  "edit.saveAsTitle": "Karte als neue Datei speichern",
  "edit.fileName": "Dateiname",
  "edit.saved": "Karte gespeichert als {file}",
  "edit.clear": "Karte löschen",
  "edit.selectAll": "Alles auswählen",
  "edit.selectedN": "{n} Objekte ausgewählt",
  "edit.vertex": "Eckpunkte bearbeiten",
  "edit.reflector": "Reflektor hinzufügen",
  "edit.circle": "Kreis hinzufügen",
  "edit.workarea": "Arbeitsbereich",
  "edit.prohibit": "Sperrzone",
  "edit.hiddenpolygon": "Verstecktes Polygon",
  "edit.label": "Beschriftung hinzufügen",
  "edit.labelText": "Beschriftungstext",
  "edit.layerFor": "Ebene für neue Objekte",
  "edit.layerNew": "{n} (neue Ebene)",
  "edit.finish": "Polygon abschließen",
  "edit.measure": "Messen",
  "edit.measured": "Abstand {d} mm (dx {dx} mm, dy {dy} mm), Richtung {a}°",
  "edit.close": "Werkzeugleiste schließen",
  "edit.closeTitle": "Ungespeicherte Änderungen",
  "edit.closeAsk":
    "Die Karte hat Änderungen, die weder gespeichert noch an die Plattform gesendet wurden. Vor dem Schließen speichern?",
  "edit.discard": "Schließen ohne Speichern",
  "edit.closed": "Karteneditor geschlossen",
  "edit.coords": "Koordinaten des ausgewählten Objekts",
  "edit.applyCoords": "Koordinaten übernehmen",
  "edit.fx": "X{n} (mm)",
  "edit.fy": "Y{n} (mm)",
  "edit.fr": "Radius (mm)",
  "edit.ftext": "Text",
  "edit.flength": "Länge (mm)",
  "edit.fdirection": "Richtung (Grad)",
  "edit.tipVertex":
    "Eckpunkte eines Polygons bearbeiten: einen Eckpunkt (zuerst des ausgewählten Objekts) an seinen neuen Ort ziehen; auf eine Polygonkante drücken fügt dort einen Eckpunkt ein; Rechtsklick auf einen Eckpunkt löscht ihn.",
  "edit.tipReflector": "Reflektor hinzufügen. Linksklick zum Beginnen, dann ziehen.",
  "edit.tipCircle": "Kreis hinzufügen. Linksklick zum Beginnen, dann ziehen.",
  "edit.tipWorkarea":
    "Arbeitsbereich als Polygon zeichnen: jeden Eckpunkt anklicken; Rechtsklick, Klick auf den ersten Eckpunkt oder Enter schließt ab (Escape verwirft). Ein neuer Arbeitsbereich ersetzt den alten.",
  "edit.tipProhibit":
    "Sperrzonen als Polygon zeichnen: jeden Eckpunkt anklicken; Rechtsklick, Klick auf den ersten Eckpunkt oder Enter schließt ab.",
  "edit.tipHiddenpolygon":
    "Verstecktes Polygon zur Kennzeichnung besonderer Bereiche einfügen; ohne Wirkung auf die Plattform. Eckpunkte anklicken; Rechtsklick oder Enter schließt ab.",
  "edit.tipLabel":
    "Beschriftung einfügen: Text im Beschriftungsfeld eingeben, dann an die Stelle klicken. Beschriftungen wirken nicht auf die Lokalisierung.",
  "edit.tipMeasure":
    "Messen: von einem Punkt zum anderen ziehen; die Enden rasten an Linienenden ein. Abstand und Richtung stehen in den Meldungen.",
  "edit.tipLoad": "Die aktuelle Karte der Plattform in den Karteneditor laden.",
  "edit.tipOpen": "Eine Karte von der Festplatte laden.",
  "edit.tipNew": "Neue Karte anlegen.",
  "edit.tipSave": "Aktuelle Karte auf der Festplatte speichern.",
  "edit.tipSaveAs": "Karte als neue Datei speichern.",
  "edit.tipSend": "Karte des Editors an die Plattform senden; sie wird aktiv.",
  "edit.tipClear": "Karte löschen.",
  "edit.tipUndo": "Rückgängig (Strg+Z)",
  "edit.tipRedo": "Wiederholen (Strg+Y)",
  "edit.tipDelete": "Ausgewählte Objekte löschen.",
  "edit.tipInvert":
    "Richtung der Linie umkehren. Der Scanner erkennt nur die Vorderseite der Linie (links mit einem Strich gezeichnet).",
  "edit.tipSelectAll": "Alle Objekte der Karte auswählen.",
  "edit.tipFromScan": "Linien aus dem Scan übernehmen.",
  "edit.tipClose": "Schließt die Werkzeugleiste und fragt, ob gespeichert werden soll.",
  "rm.pathPoints": "Pfadpunkte bearbeiten",
  "rm.tipPathPoints":
    "Eine Kante anklicken, dann auf die Karte klicken, um ihr einen Pfadpunkt hinzuzufügen; Pfadpunkte ziehen zum Verschieben, Rechtsklick zum Löschen.",
  "rm.edgeSelected": "Kante {from} -> {to} ausgewählt: {n} Pfadpunkte",
  "rm.pathChanged": "Pfadpunkte der Kante {from} -> {to}: {n}",
  "rm.noEdge": "Zuerst eine Kante anklicken",
  "rm.open": "Straßenkarten-Datei öffnen",
  "rm.opened": "Straßenkarten-Datei {file} im Editor geöffnet: {n} Stationen, {e} Kanten",
  "rm.saveAsTitle": "Straßenkarte als neue Datei speichern",
  "rm.saved": "Straßenkarte gespeichert als {file}",
  "rm.closeAsk":
    "Die Straßenkarte hat Änderungen, die weder gespeichert noch an die Plattform gesendet wurden. Vor dem Schließen speichern?",
  "rm.closed": "Straßenkarteneditor geschlossen",
};

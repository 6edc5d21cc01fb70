package model

// Documents: the active map, roadmap and program (guide 6.3 CMD_SET_MAP ... CMD_SAVE_PROGRAM).
//
// Rules:
//   - A document is kept as sent: GET returns exactly the bytes (and name) SET got (E-XML-011: "the same
//     document"). SET and LOAD refuse a document that is not well-formed, has the wrong root element, declares
//     entities, is invalid against its schema of spec/schemas or is over 8 MiB (xmldoc.go); the active
//     document stays.
//   - LOAD/SAVE use the platform's fixed files (E-CMD-008) on a Disk; after LOAD or at start-up the name is
//     the file name (E-SRV-011). LOAD of a missing file and SAVE without an active document are refused.
//   - No active document: GET returns empty XML and an empty name (E-SRV-011).

import (
	"errors"
	"path"
	"unicode/utf8"
)

// MaxDocument is the largest document accepted (E-XML-021: 8 MiB).
const MaxDocument = 8 << 20

// Disk is where LOAD and SAVE find the platform's files (a directory, or memory in tests).
type Disk interface {
	Read(name string) ([]byte, error)
	Write(name string, data []byte) error
}

// MemDisk is a Disk in memory (the default without --data-dir: empty at start).
type MemDisk map[string][]byte

func (m MemDisk) Read(name string) ([]byte, error) {
	if b, ok := m[name]; ok {
		return append([]byte{}, b...), nil
	}
	return nil, errors.New("no such file")
}

func (m MemDisk) Write(name string, data []byte) error {
	m[name] = append([]byte{}, data...)
	return nil
}

// DocKind is map, roadmap or program.
type DocKind int

// The kinds, with their files (E-CMD-008).
const (
	MapDoc DocKind = iota
	RoadmapDoc
	ProgramDoc
)

var docFiles = [...]string{"Map/PltfMap.map", "Roadmap/PltfRoadmap.rm", "Program/PltfProgram.xml"}
var docNames = [...]string{"map", "roadmap", "program"}

func (k DocKind) String() string { return docNames[k] }

// Document is one active document; XML holds the bytes one rune per byte (Latin-1, E-WIRE-003), as the codec does.
type Document struct {
	Name, XML string
	Active    bool
}

// Documents holds the three active documents.
type Documents struct {
	Active [3]Document
	Disk   Disk
}

// Set makes a document active as sent.
func (d *Documents) Set(k DocKind, name, xml string) error {
	if utf8.RuneCountInString(xml) > MaxDocument { // one rune per byte (Latin-1)
		return errors.New("document over 8 MiB (E-XML-021)")
	}
	if err := checkKind(bytesOf(xml), k); err != nil {
		return err
	}
	d.Active[k] = Document{Name: name, XML: xml, Active: true}
	return nil
}

// Load makes the stored file active under its file name.
func (d *Documents) Load(k DocKind) error {
	b, err := d.Disk.Read(docFiles[k])
	if err != nil {
		return errors.New("no stored " + k.String() + " (" + docFiles[k] + ")")
	}
	if len(b) > MaxDocument {
		return errors.New("stored document over 8 MiB (E-XML-021)")
	}
	if err := checkKind(b, k); err != nil {
		return errors.New("stored " + k.String() + ": " + err.Error())
	}
	name := ""
	if k != ProgramDoc {
		name = path.Base(docFiles[k])
	}
	d.Active[k] = Document{Name: name, XML: latin1(b), Active: true}
	return nil
}

// Save writes the active document to its file.
func (d *Documents) Save(k DocKind) error {
	a := d.Active[k]
	if !a.Active {
		return errors.New("no active " + k.String())
	}
	return d.Disk.Write(docFiles[k], bytesOf(a.XML))
}

func latin1(b []byte) string {
	r := make([]rune, len(b))
	for i, c := range b {
		r[i] = rune(c)
	}
	return string(r)
}

func bytesOf(s string) []byte {
	b := make([]byte, 0, len(s))
	for _, r := range s {
		b = append(b, byte(r))
	}
	return b
}

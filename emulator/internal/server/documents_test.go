package server

// Documents over TCP: kept as sent (guide 6.3 CMD_SET_MAP ... CMD_GET_PROGRAM; E-XML-011, E-REP-013, E-REP-014,
// E-SRV-011), byte-exact against fixtures/vectors: the request vector sent raw, the reply compared with the
// reply vector that carries the same document.

import (
	"bytes"
	"testing"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

func TestDocumentsComeBackAsSent(t *testing.T) {
	requests, replies := loadVectors(t, "requests.json"), loadVectors(t, "replies.json")
	h := start(t)
	c := h.dial(h.ports[0])
	for _, pair := range []struct{ set, get, reply string }{
		{"", "get_map", "reply_get_map_none"}, // E-SRV-011: no active document: empty XML and name
		{"", "get_program", "reply_get_program_none"},
		{"set_map_office", "get_map", "reply_get_map"},
		{"set_map_latin1", "get_map", "reply_get_map_latin1"}, // ISO-8859-1 declared, a non-ASCII name
		{"set_roadmap", "get_roadmap", "reply_get_roadmap"},
		{"set_program", "get_program", "reply_get_program"},
	} {
		if pair.set != "" {
			c.write(requests[pair.set].bytes(t))
		}
		c.write(requests[pair.get].bytes(t))
		got, err := c.readFrame()
		if err != nil {
			t.Fatalf("%s: %v", pair.get, err)
		}
		if want := replies[pair.reply].bytes(t); !bytes.Equal(got, want) {
			t.Errorf("%s after %s: %d bytes, not the %d of %s", pair.get, pair.set, len(got), len(want), pair.reply)
		}
	}
}

func TestMalformedDocumentsAreRefused(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	good := `<?xml version="1.0"?><map Version="1.0"><layer/></map>`
	c.send(&pc.SetMapRequest{Name: "good.map", XML: good})
	for _, bad := range []string{
		"",
		"this is not a document",
		`<?xml version="1.0"?><map Version="1.0"><layer/>`,
		`<?xml version="1.0"?><roadmap><stations/><edges/></roadmap>`,
		`<?xml version="1.0"?><!DOCTYPE map [<!ENTITY a "aaaa">]><map>&a;</map>`,
		`<?xml version="1.0"?><!DOCTYPE map [<!ENTITY x SYSTEM "file:///etc/passwd">]><map>&x;</map>`,
		`<?xml version="1.0" encoding="UTF-8"?><map name="` + "\u00ff" + `"/>`, // not UTF-8 (E-XML-011)
		`<map/><map/>`,
		`<?xml version="1.0"?><map Version="1.0"><layer><line><point x="0" y="0"/></line></layer></map>`, // E-XML: the schema
		`<?xml version="1.0"?><map Version="1.0"><layer><fly/></layer></map>`,
	} {
		c.send(&pc.SetMapRequest{Name: "bad.map", XML: bad})
		if r := c.get(&pc.GetMapRequest{}).(*pc.GetMapReply); r.XML != good || r.Name != "good.map" {
			t.Errorf("after %q the active map is %q (%q)", bad, r.XML, r.Name)
		}
	}
	// a DOCTYPE without entities is allowed (E-XML-012), and so is a declared ISO-8859-1 byte
	for _, ok := range []string{
		`<?xml version="1.0"?><!DOCTYPE map SYSTEM "map.dtd"><map/>`,
		`<?xml version="1.0" encoding="ISO-8859-1"?><map><layer><hiddenlabel text="B` + "\u00fc" +
			`ro"><point x="0" y="0"/></hiddenlabel></layer></map>`,
	} {
		c.send(&pc.SetMapRequest{Name: "ok.map", XML: ok})
		if r := c.get(&pc.GetMapRequest{}).(*pc.GetMapReply); r.XML != ok {
			t.Errorf("%q was refused", ok)
		}
	}
}

func TestSaveThenLoad(t *testing.T) {
	disk := model.MemDisk{}
	h := startWith(t, model.Options{Disk: disk}, nil)
	c := h.dial(h.ports[0])
	c.send(&pc.LoadRoadmapRequest{}) // nothing stored yet: refused, nothing active
	if r := c.get(&pc.GetRoadmapRequest{}).(*pc.GetRoadmapReply); r.XML != "" {
		t.Fatalf("LOAD of a missing file made %q active", r.XML)
	}
	first := `<roadmap><stations/><edges/></roadmap>`
	c.send(&pc.SetRoadmapRequest{Name: "mine.rm", XML: first}, &pc.SaveRoadmapRequest{},
		&pc.SetRoadmapRequest{Name: "other.rm", XML: `<roadmap Version="2"><stations/><edges/></roadmap>`},
		&pc.LoadRoadmapRequest{})
	r := c.get(&pc.GetRoadmapRequest{}).(*pc.GetRoadmapReply)
	if r.XML != first || r.Name != "PltfRoadmap.rm" { // E-SRV-011: after LOAD the name is the file name
		t.Fatalf("after SAVE, SET, LOAD: %q %q", r.XML, r.Name)
	}
	if string(disk["Roadmap/PltfRoadmap.rm"]) != first {
		t.Fatalf("stored %q", disk["Roadmap/PltfRoadmap.rm"])
	}
}

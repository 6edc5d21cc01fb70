package xsd

import (
	"bytes"
	"encoding/xml"
	"io"
	"os"
	"path/filepath"
	"strings"
	"testing"

	"pltf/emulator/internal/xsd/schemagen"
)

func TestSchemasAreCurrent(t *testing.T) {
	want, err := schemagen.Render(filepath.Join("..", "..", "..", "spec", "schemas"))
	if err != nil {
		t.Fatal(err)
	}
	have, err := os.ReadFile("schemas_gen.go")
	if err != nil || !bytes.Equal(have, want) {
		t.Fatal("internal/xsd/schemas_gen.go is stale: run `go run ./cmd/genspec` in emulator/")
	}
}

func compile(t *testing.T, file string) *Schema {
	t.Helper()
	s, err := Compile(file, func(name string) ([]byte, error) {
		if src, ok := Files[name]; ok {
			return []byte(src), nil
		}
		return nil, os.ErrNotExist
	})
	if err != nil {
		t.Fatal(err)
	}
	return s
}

func plain(r io.Reader) *xml.Decoder { d := xml.NewDecoder(r); d.Strict = true; return d }

func fixture(t *testing.T, path string) []byte {
	b, err := os.ReadFile(filepath.Join("..", "..", "..", "fixtures", path))
	if err != nil {
		t.Fatal(err)
	}
	return b
}

// TestFixtures: the fixtures' valid documents validate, the invalid ones do not (fixtures/invalid names why).
func TestFixtures(t *testing.T) {
	schemas := map[string]*Schema{"map": compile(t, "map.xsd"), "roadmap": compile(t, "roadmap.xsd"),
		"program": compile(t, "program.xsd"), "task": compile(t, "task.xsd")}
	for path, kind := range map[string]string{"maps/office.map": "map", "roadmaps/office.rm": "roadmap",
		"programs/patrol.xml": "program", "programs/every_element.xml": "program"} {
		if err := schemas[kind].Validate(fixture(t, path), plain); err != nil {
			t.Errorf("%s: %v", path, err)
		}
	}
	for path, kind := range map[string]string{"invalid/missing_point.map": "map", "invalid/wrong_root.map": "map",
		"invalid/dangling_edge.rm": "roadmap", "invalid/bad_number.rm": "roadmap",
		"invalid/unknown_element.xml": "program", "invalid/bad_digitalout.task": "task"} {
		if err := schemas[kind].Validate(fixture(t, path), plain); err == nil {
			t.Errorf("%s validates", path)
		}
	}
}

func TestTheRules(t *testing.T) {
	m, r, p := compile(t, "map.xsd"), compile(t, "roadmap.xsd"), compile(t, "program.xsd")
	pt := func(x, y string) string { return `<point x="` + x + `" y="` + y + `"/>` }
	line := `<line>` + pt("0", "0") + pt("1", "1") + `</line>`
	for _, c := range []struct {
		s   *Schema
		doc string
		ok  bool
	}{
		{m, `<map/>`, true},
		{m, `<map Version="1.0"><layer index="3">` + line + line + `<reflmark>` + pt("1", "2") + `</reflmark></layer></map>`, true},
		{m, `<map><layer><line>` + pt("0", "0") + `</line></layer></map>`, false},                               // minOccurs 2
		{m, `<map><layer><line>` + pt("0", "0") + pt("1", "1") + pt("2", "2") + `</line></layer></map>`, false}, // maxOccurs 2
		{m, `<map><layer>` + line + `<fly/></layer></map>`, false},
		{m, `<map><layer><line>` + pt(" 2147483647 ", "-2147483647.0") + pt("+.5", "7.") + `</line></layer></map>`, true},
		{m, `<map><layer><line>` + pt("2147483648", "0") + pt("0", "0") + `</line></layer></map>`, false}, // E-XML-025
		{m, `<map><layer><line>` + pt("2147483647.0000000000000000000000000000000001", "0") + pt("0", "0") + `</line></layer></map>`, false},
		{m, `<map><layer><line>` + pt("1"+strings.Repeat("0", 5000), "0") + pt("0", "0") + `</line></layer></map>`, false},
		{m, `<map><layer><line>` + pt("1e3", "0") + pt("0", "0") + `</line></layer></map>`, false}, // E-XML-006
		{m, `<map><layer><line><point x="1"/>` + pt("0", "0") + `</line></layer></map>`, false},    // required y
		{m, `<map><layer><line><point x="1" y="2" z="3"/>` + pt("0", "0") + `</line></layer></map>`, false},
		{m, `<map><layer><hiddenlabel text="a b">text is tolerated` + pt("0", "0") + `</hiddenlabel></layer></map>`, true},
		{m, `<map><layer>text<circle><center x="1" y="1"/><radius r="-1"/></circle></layer></map>`, false},
		{m, `<map><layer index="1.5"/></map>`, false},
		{m, `<roadmap/>`, false},
		{r, `<roadmap><stations><station id="a">` + pt("0", "0") + `</station><station id="b">` + pt("1", "0") +
			`</station></stations><edges><edge startstation="a" endstation="b"><points>` + pt("5", "5") +
			`</points></edge><edge startstation="b" endstation="a">` + pt("5", "5") + `</edge></edges></roadmap>`, true},
		{r, `<roadmap><stations><station id="a">` + pt("0", "0") + `</station><station id="a">` + pt("1", "0") +
			`</station></stations><edges/></roadmap>`, false}, // a duplicate ID
		{r, `<roadmap><stations><station id="1">` + pt("0", "0") + `</station></stations><edges/></roadmap>`, false},
		{r, `<roadmap><stations/><edges/><stations/></roadmap>`, false},
		{r, `<roadmap><edges/></roadmap>`, false},
		{p, `<program><task name="t"><goto label="x" condition="DI3==1"/><goto label="x" condition="DI17==1"/></task></program>`, false},
		{p, `<program><task name="t"><goto label="x" condition="param:MaxTransVel!=600"/><wait/><motion stop="1"/></task></program>`, true},
		{p, `<program><task><motion><settarget><coord x="1" y="2"/></settarget><moveto><trackedball/></moveto></motion></task></program>`, false},
		{p, `<program><task><ioevent><digitalout D1="-1" D12="1"/></ioevent><wait><date month="13"/></wait></task></program>`, false},
		{p, `<program><task><parameter><set key="a b" value="1"/></parameter></task></program>`, false},
		{p, `<task/>`, true}, // program.xsd includes task.xsd: both are global (the emulator checks the root first)
	} {
		if err := c.s.Validate([]byte(c.doc), plain); (err == nil) != c.ok {
			t.Errorf("%.120s: %v, want ok=%v", c.doc, err, c.ok)
		}
	}
}

// TestIDREFWithoutKeyref: an IDREF must name an ID of the document even where no xs:keyref says so.
func TestIDREFWithoutKeyref(t *testing.T) {
	src := `<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">
	  <xs:element name="r"><xs:complexType><xs:sequence>
	    <xs:element name="a" minOccurs="0" maxOccurs="unbounded"><xs:complexType>
	      <xs:attribute name="id" type="xs:ID"/><xs:attribute name="to" type="xs:IDREF"/>
	    </xs:complexType></xs:element>
	  </xs:sequence></xs:complexType></xs:element>
	</xs:schema>`
	s, err := Compile("x.xsd", func(string) ([]byte, error) { return []byte(src), nil })
	if err != nil {
		t.Fatal(err)
	}
	if err := s.Validate([]byte(`<r><a id="p"/><a to="p"/></r>`), plain); err != nil {
		t.Fatal(err)
	}
	if err := s.Validate([]byte(`<r><a id="p"/><a to="q"/></r>`), plain); err == nil {
		t.Fatal("a dangling IDREF validates")
	}
	if _, err := Compile("y.xsd", func(string) ([]byte, error) {
		return []byte(`<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema"><xs:group name="g"/></xs:schema>`), nil
	}); err == nil {
		t.Fatal("an unsupported construct compiled")
	}
}

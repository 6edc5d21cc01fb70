package params

import (
	"bytes"
	"math"
	"os"
	"path/filepath"
	"testing"

	"pltf/emulator/internal/params/specgen"
)

// TestTableIsCurrent: table_gen.go is what `go run ./cmd/genspec` writes from spec/ today.
func TestTableIsCurrent(t *testing.T) {
	spec := filepath.Join("..", "..", "..", "spec")
	p, err1 := os.ReadFile(filepath.Join(spec, "parameters.yaml"))
	e, err2 := os.ReadFile(filepath.Join(spec, "enums.yaml"))
	have, err3 := os.ReadFile("table_gen.go")
	if err1 != nil || err2 != nil || err3 != nil {
		t.Fatal(err1, err2, err3)
	}
	entries, err := specgen.Parse(p, e)
	if err != nil {
		t.Fatal(err)
	}
	want, err := specgen.Render(entries)
	if err != nil {
		t.Fatal(err)
	}
	if !bytes.Equal(have, want) {
		t.Fatal("internal/params/table_gen.go is stale: run `go run ./cmd/genspec` in emulator/")
	}
}

func TestTableRows(t *testing.T) {
	if len(Table) != 104 {
		t.Fatalf("%d parameters, spec/parameters.yaml has 104", len(Table))
	}
	s := NewStore()
	p, ok := s.Lookup("IpoRotVel") // E-PAR-002, E-PAR-015: DOUBLE rad/s 0.6 in 0.05..1.5, category IPO (2)
	if !ok || p.Type != Double || p.Default != 0.6 || p.Min != 0.05 || p.Max != 1.5 || p.Category != 2 || !p.Writable {
		t.Fatalf("IpoRotVel %+v", p)
	}
	if lo, hi := p.WireBounds(); lo != 0 || hi != 2 { // E-PAR-004: floor(min), ceil(max)
		t.Fatalf("wire bounds %d %d", lo, hi)
	}
	if p, _ := s.Lookup("MaxTransVel"); p.Writable || p.Unit != "mm/s" {
		t.Fatalf("MaxTransVel %+v (E-PAR-023, E-PAR-024)", p)
	}
	if _, ok := NewStore("VelWatchdogTime").Lookup("VelWatchdogTime"); ok {
		t.Fatal("an omitted parameter is offered")
	}
}

func TestParse(t *testing.T) {
	ok := []struct {
		typ  int
		text string
		want float64
	}{
		{Boolean, "true", 1}, {Boolean, " FALSE\n", 0}, {Boolean, "1", 1}, {Boolean, "0", 0}, {Boolean, "True", 1},
		{Integer, "-42", -42}, {Integer, "+7", 7}, {Integer, "\t1000 ", 1000}, {Integer, "2147483647", 2147483647},
		{Double, "0.6", 0.6}, {Double, ".5", 0.5}, {Double, "-1e-3", -0.001}, {Double, "1000", 1000}, {Double, "2E2", 200},
	}
	for _, c := range ok {
		if got, err := Parse(c.typ, c.text); err != nil || got != c.want {
			t.Errorf("Parse(%d, %q) = %v, %v; want %v", c.typ, c.text, got, err, c.want)
		}
	}
	for _, c := range []struct {
		typ  int
		text string
	}{
		{Boolean, "on"}, {Boolean, "yes"}, {Boolean, ""}, {Boolean, "2"},
		{Integer, "1.0"}, {Integer, "1e3"}, {Integer, "0x10"}, {Integer, "1_000"}, {Integer, "2147483648"}, {Integer, ""},
		{Double, "nan"}, {Double, "inf"}, {Double, "-Infinity"}, {Double, "1."}, {Double, "0,6"}, {Double, "1e400"},
		{Double, "0x1p3"}, {Double, "1 2"},
	} {
		if v, err := Parse(c.typ, c.text); err == nil {
			t.Errorf("Parse(%d, %q) = %v, want a refusal", c.typ, c.text, v)
		}
	}
}

func TestFormat(t *testing.T) {
	for _, c := range []struct {
		typ  int
		v    float64
		want string
	}{
		{Boolean, 1, "true"}, {Boolean, 0, "false"}, {Integer, -5, "-5"}, {Integer, 1000, "1000"},
		{Double, 0.6, "0.6"}, {Double, 1000, "1000.0"}, {Double, 1e-05, "1e-05"}, {Double, 0.0001, "0.0001"},
		{Double, 430, "430.0"}, {Double, 1e16, "1e+16"}, {Double, math.Nextafter(0.3, 1), "0.30000000000000004"},
	} {
		if got := Format(c.typ, c.v); got != c.want {
			t.Errorf("Format(%d, %v) = %q, want %q", c.typ, c.v, got, c.want)
		}
	}
}

func TestSetRefusesAsAWhole(t *testing.T) {
	s := NewStore()
	if err := s.Set("IpoTransVel", "600"); err != nil || s.Value("IpoTransVel", 0) != 600 {
		t.Fatal(err)
	}
	for _, bad := range [][2]string{{"IpoTransVel", "2000"}, {"IpoTransVel", "x"}, {"MaxRotVel", "1"}, {"ipotransvel", "700"}} {
		if err := s.Set(bad[0], bad[1]); err == nil {
			t.Errorf("SET %s %s accepted", bad[0], bad[1])
		}
	}
	if s.Value("IpoTransVel", 0) != 600 {
		t.Fatal("a refused SET changed the value")
	}
}

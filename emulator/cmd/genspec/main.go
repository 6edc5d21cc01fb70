// genspec writes the emulator's generated copies of spec/: internal/params/table_gen.go from
// spec/parameters.yaml and spec/enums.yaml, internal/xsd/schemas_gen.go from spec/schemas/*.xsd,
// internal/ids/ids_gen.go (the telegram ids by name) from spec/telegrams.json.
// Run from emulator/: go run ./cmd/genspec (tests fail while a copy is stale).
package main

import (
	"fmt"
	"os"

	"pltf/emulator/internal/ids/idsgen"
	"pltf/emulator/internal/params/specgen"
	"pltf/emulator/internal/xsd/schemagen"
)

func main() {
	if err := run(); err != nil {
		fmt.Fprintln(os.Stderr, "genspec:", err)
		os.Exit(1)
	}
}

func run() error {
	p, err1 := os.ReadFile("../spec/parameters.yaml")
	e, err2 := os.ReadFile("../spec/enums.yaml")
	if err1 != nil || err2 != nil {
		return fmt.Errorf("run from emulator/ (reads ../spec/parameters.yaml and ../spec/enums.yaml)")
	}
	entries, err := specgen.Parse(p, e)
	if err != nil {
		return err
	}
	src, err := specgen.Render(entries)
	if err != nil {
		return err
	}
	if err := os.WriteFile("internal/params/table_gen.go", src, 0o644); err != nil {
		return err
	}
	schemas, err := schemagen.Render("../spec/schemas")
	if err != nil {
		return err
	}
	if err := os.WriteFile("internal/xsd/schemas_gen.go", schemas, 0o644); err != nil {
		return err
	}
	telegrams, err := writeIDs()
	if err != nil {
		return err
	}
	fmt.Printf("internal/params/table_gen.go: %d parameters; internal/xsd/schemas_gen.go; "+
		"internal/ids/ids_gen.go: %d telegrams\n", len(entries), telegrams)
	return nil
}

func writeIDs() (int, error) {
	raw, err := os.ReadFile("../spec/telegrams.json")
	if err != nil {
		return 0, fmt.Errorf("run from emulator/ (reads ../spec/telegrams.json)")
	}
	entries, err := idsgen.Parse(raw)
	if err != nil {
		return 0, err
	}
	src, err := idsgen.Render(entries)
	if err != nil {
		return 0, err
	}
	return len(entries), os.WriteFile("internal/ids/ids_gen.go", src, 0o644)
}

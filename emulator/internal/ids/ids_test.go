package ids

import (
	"bytes"
	"errors"
	"os"
	"path/filepath"
	"strings"
	"testing"

	pc "platformctrl"

	"pltf/emulator/internal/ids/idsgen"
)

// TestIDsAreCurrent: ids_gen.go is what `go run ./cmd/genspec` writes from spec/ today.
func TestIDsAreCurrent(t *testing.T) {
	raw, err1 := os.ReadFile(filepath.Join("..", "..", "..", "spec", "telegrams.json"))
	have, err2 := os.ReadFile("ids_gen.go")
	if err1 != nil || err2 != nil {
		t.Fatal(err1, err2)
	}
	entries, err := idsgen.Parse(raw)
	if err != nil {
		t.Fatal(err)
	}
	want, err := idsgen.Render(entries)
	if err != nil {
		t.Fatal(err)
	}
	if !bytes.Equal(have, want) {
		t.Fatal("internal/ids/ids_gen.go is stale: run `go run ./cmd/genspec` in emulator/")
	}
}

// TestIDsAreTheCodecs: every named id is the request of that name in the generated client codec, which
// pltf.stubgen writes from the same spec (two generators, one answer).
func TestIDsAreTheCodecs(t *testing.T) {
	if len(Names) != 70 {
		t.Fatalf("%d telegram ids, spec/telegrams.yaml has 70", len(Names))
	}
	for id, name := range Names {
		tg, err := pc.DecodeData([]byte{id}, pc.Request)
		var perr *pc.ProtocolError
		switch {
		case err == nil && tg.TelegramName() != name:
			t.Errorf("id %d: the codec decodes %s, ids names %s", id, tg.TelegramName(), name)
		case errors.As(err, &perr) && perr.Kind == "UnknownTelegram":
			t.Errorf("id %d (%s): unknown to the codec", id, name)
		case err != nil && (perr == nil || !strings.HasPrefix(perr.Msg, name+".") && !strings.HasPrefix(perr.Msg, name+".") && !strings.HasPrefix(perr.Msg, name+":")):
			t.Errorf("id %d: the codec's error %q does not name %s", id, err, name)
		}
	}
	if SetMode != (&pc.SetModeRequest{}).TelegramID() || GetPosition != (&pc.GetPositionRequest{}).TelegramID() {
		t.Fatal("SetMode or GetPosition differs from the codec's")
	}
}

func TestGoName(t *testing.T) {
	for in, want := range map[string]string{"CMD_SET_MODE": "SetMode", "CMD_ADD_CAN_LISTENING_ID": "AddCanListeningId",
		"CMD_GET_MAPIMAGE": "GetMapimage", "CMD_DEBUG1": "Debug1"} {
		if got := idsgen.GoName(in); got != want {
			t.Errorf("GoName(%s) = %s, want %s", in, got, want)
		}
	}
}

func TestParseRefusesDuplicates(t *testing.T) {
	dup := []byte(`{"data": {"telegrams": [{"name": "CMD_A", "id": 1}, {"name": "CMD_B", "id": 1}]}}`)
	if _, err := idsgen.Parse(dup); err == nil {
		t.Fatal("two telegrams with id 1 were accepted")
	}
	if _, err := idsgen.Parse([]byte(`{"data": {"telegrams": [{"name": "X", "id": 1}]}}`)); err == nil {
		t.Fatal("a name without CMD_ was accepted")
	}
}

// namesIt: a codec error about a telegram starts with its name ("CMD_SET_MODE.mode: ..." or "CMD_X: ...").
func namesIt(msg, name string) bool {
	return strings.HasPrefix(msg, name+".") || strings.HasPrefix(msg, name+":")
}

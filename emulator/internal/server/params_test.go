package server

// Parameters over TCP (guide 6.3 CMD_SET_PLTF_PARAM, CMD_GET_PLTF_PARAM, CMD_GET_PLTF_PARAM_VEC; E-PAR-003..007,
// E-SRV-010), byte-exact against fixtures/vectors where a vector holds a default value.

import (
	"bytes"
	"encoding/hex"
	"testing"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

// TestDefaultsAreTheVectorsBytes: a fresh emulator answers GET_PLTF_PARAM IpoRotVel and IpoTransVel with
// exactly the frames of the reply vectors (their values are the spec's defaults).
func TestDefaultsAreTheVectorsBytes(t *testing.T) {
	replies := loadVectors(t, "replies.json")
	requests := loadVectors(t, "requests.json")
	h := start(t)
	c := h.dial(h.ports[0])
	for key, vec := range map[string]string{"IpoRotVel": "reply_get_pltf_param_double", "IpoTransVel": "reply_get_pltf_param_integer"} {
		c.send(&pc.GetPltfParamRequest{Key: key})
		got, err := c.readFrame()
		if err != nil {
			t.Fatal(err)
		}
		if want := replies[vec].bytes(t); !bytes.Equal(got, want) {
			t.Errorf("GET_PLTF_PARAM %s:\n got  %x\n want %x", key, got, want)
		}
	}
	// the request vector get_pltf_param (IpoTransVel), sent as raw bytes, gets the same reply
	c.write(requests["get_pltf_param"].bytes(t))
	got, _ := c.readFrame()
	if want := replies["reply_get_pltf_param_integer"].bytes(t); !bytes.Equal(got, want) {
		t.Errorf("raw get_pltf_param vector: got %x", got)
	}
}

func param(c *conn, key string) *pc.GetPltfParamReply {
	return c.get(&pc.GetPltfParamRequest{Key: key}).(*pc.GetPltfParamReply)
}

func TestSetThenGet(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	cases := []struct{ key, text, want string }{
		{"IpoTransVel", "600", "600"},
		{"IpoTransVel", " +700\r\n", "700"}, // E-PAR-006: blanks stripped, a sign allowed
		{"IpoRotVel", "0.75", "0.75"},
		{"IpoRotVel", "1", "1.0"}, // an integer text is a DOUBLE; written back in the shortest round-trip form
		{"IpoRotVel", "1.2e-1", "0.12"},
		{"EndTurnEnabled", "FALSE", "false"}, // E-PAR-005: any letter case; E-PAR-027: reported lower-case
		{"EndTurnEnabled", "1", "true"},
		{"LineExtractMaxCov", "0.00005", "5e-05"},
	}
	for _, tc := range cases {
		c.send(&pc.SetPltfParamRequest{Key: tc.key, Value: tc.text})
		if got := param(c, tc.key).Value; got != tc.want {
			t.Errorf("SET %s %q: GET gives %q, want %q", tc.key, tc.text, got, tc.want)
		}
	}
}

func TestRefusedSetKeepsTheOldValue(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	refused := []struct{ key, text string }{
		{"IpoTransVel", "49"},     // below the range 50..1500
		{"IpoTransVel", "1501"},   // above
		{"IpoTransVel", "1000.5"}, // INTEGER: no fraction (E-PAR-006)
		{"IpoTransVel", "0x3e8"},  // no hex
		{"IpoTransVel", "99999999999"},
		{"IpoRotVel", "nan"},
		{"IpoRotVel", "inf"},
		{"IpoRotVel", "0,6"}, // no decimal comma
		{"IpoRotVel", "1e999"},
		{"EndTurnEnabled", "on"}, // E-PAR-005: refused
		{"EndTurnEnabled", "yes"},
		{"MaxTransVel", "1000"}, // read-only (E-PAR-024)
		{"iporotvel", "0.7"},    // keys are exact (E-PAR-003)
		{"Planning Enabled", "false"},
	}
	before := c.get(&pc.GetPltfParamVecRequest{}).(*pc.GetPltfParamVecReply).Parameters
	for _, r := range refused {
		c.send(&pc.SetPltfParamRequest{Key: r.key, Value: r.text})
	}
	after := c.get(&pc.GetPltfParamVecRequest{}).(*pc.GetPltfParamVecReply).Parameters
	if len(after) != len(before) {
		t.Fatalf("%d parameters before, %d after", len(before), len(after))
	}
	for i := range before {
		if before[i] != after[i] {
			t.Errorf("%s changed from %q to %q", before[i].Key, before[i].Value, after[i].Value)
		}
	}
}

func TestUnknownKeyIsAnsweredEmpty(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	// E-SRV-010: (key, "", 0, 0, 0, 0); hand-encoded: id 38, INT 4 "Nope", INT 0, BYTE 0, BYTE 0, INT 0, INT 0
	c.send(&pc.GetPltfParamRequest{Key: "Nope"})
	got, _ := c.readFrame()
	want, _ := hex.DecodeString("ff01fe0200000017" + "26" + "00000004" + "4e6f7065" + "00000000" + "00" + "00" + "00000000" + "00000000")
	if !bytes.Equal(got, want) {
		t.Fatalf("got %x\nwant %x", got, want)
	}
}

func TestParamVecListsTheTable(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	vec := c.get(&pc.GetPltfParamVecRequest{}).(*pc.GetPltfParamVecReply).Parameters
	// spec/parameters.yaml has 104 parameters; without a velocity watchdog VelWatchdogTime is not offered
	if len(vec) != 103 {
		t.Fatalf("%d parameters", len(vec))
	}
	if vec[0].Key != "FlashlightEnabled" || vec[0].Value != "false" || vec[0].Category != pc.Surveillance {
		t.Errorf("first entry %+v (E-PAR-026: the spec's order)", vec[0])
	}
	for _, e := range vec {
		if e.Key == "VelWatchdogTime" {
			t.Error("VelWatchdogTime offered without a watchdog")
		}
		if e.Key == "DistWheels" && (e.Value != "430.0" || e.Minimum != 100 || e.Maximum != 2000 || e.DataType != 2) {
			t.Errorf("DistWheels %+v", e)
		}
	}
	// with a watchdog configured it is offered, with its value
	h2 := startWith(t, model.Options{VelWatchdog: 0.8}, nil)
	if got := param(h2.dial(h2.ports[0]), "VelWatchdogTime"); got.Value != "800" || got.Minimum != 50 {
		t.Errorf("VelWatchdogTime %+v", got)
	}
}

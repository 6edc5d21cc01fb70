package server

// The state chart over TCP, cell by cell: every chart command in every state, observed in GET_STATUS
// (guide 4.2 figure 2, 6.3; errata E-SRV-001..004, E-SRV-018). The expected table is written here from the
// errata, not taken from the model's table.

import (
	"testing"

	pc "platformctrl"
)

type st string

const (
	nc st = "not-connected"
	co st = "connected"
	rd st = "ready"
	ru st = "running"
	br st = "breaked"
)

var pathTo = map[st][]pc.Telegram{
	nc: {},
	co: {&pc.ConnectToPltfRequest{}},
	rd: {&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}},
	ru: {&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}, &pc.StartRequest{}},
	br: {&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}, &pc.StartRequest{}, &pc.BreakRequest{}},
}

// allowedCells: where an allowed command leads; every other (state, command) pair changes nothing.
var allowedCells = map[st]map[string]st{
	nc: {"CMD_CONNECT_TO_PLTF": co},
	co: {"CMD_INIT_PLTF": rd, "CMD_SHUTDOWN_PLTF": nc},
	rd: {"CMD_SHUTDOWN_PLTF": nc, "CMD_START": ru, "CMD_SET_MODE": rd},
	ru: {"CMD_SHUTDOWN_PLTF": nc, "CMD_BREAK": br, "CMD_STOP": rd},
	br: {"CMD_SHUTDOWN_PLTF": nc, "CMD_CONTINUE": ru, "CMD_STOP": rd},
}

var chartCommands = []pc.Telegram{
	&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}, &pc.ShutdownPltfRequest{}, &pc.StartRequest{},
	&pc.BreakRequest{}, &pc.ContinueRequest{}, &pc.StopRequest{}, &pc.SetModeRequest{Mode: pc.ModeMotionVel},
}

// observe tells the state from GET_STATUS; the two NOT_INITIALIZED states apart by what CMD_INIT_PLTF does.
func observe(c *conn) (st, pc.MotionMode) {
	s := c.status()
	switch s.OperationState {
	case pc.StOpReady:
		return rd, s.MotionMode
	case pc.StOpRunning:
		return ru, s.MotionMode
	case pc.StOpBreaked:
		return br, s.MotionMode
	}
	if s.Initialized != pc.Off {
		c.t.Fatalf("ST_OP_NOT_INITIALIZED with initialized = %d (E-SRV-001)", s.Initialized)
	}
	c.send(&pc.InitPltfRequest{})
	if c.status().OperationState == pc.StOpReady {
		return co, s.MotionMode
	}
	return nc, s.MotionMode
}

func TestEveryChartCell(t *testing.T) {
	for _, from := range []st{nc, co, rd, ru, br} {
		for _, cmd := range chartCommands {
			h := start(t)
			c := h.dial(h.ports[0])
			c.send(pathTo[from]...)
			c.send(cmd)
			want, ok := allowedCells[from][cmd.TelegramName()]
			if !ok {
				want = from
			}
			got, mode := observe(c)
			if got != want {
				t.Errorf("%s in %s: now %s, want %s", cmd.TelegramName(), from, got, want)
			}
			wantMode := pc.ModeMotionNo
			if cmd.TelegramName() == "CMD_SET_MODE" && from == rd {
				wantMode = pc.ModeMotionVel
			}
			if mode != wantMode {
				t.Errorf("%s in %s: motion mode %d, want %d", cmd.TelegramName(), from, mode, wantMode)
			}
		}
	}
}

func TestStatusFlagsFollowTheChart(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[1])
	s := c.status()
	if s.OperationState != pc.StOpNotInitialized || s.Initialized != pc.Off || s.MotorLeftStatus != -1 {
		t.Fatalf("at start: state %d initialized %d motor status %d", s.OperationState, s.Initialized, s.MotorLeftStatus)
	}
	c.send(&pc.ConnectToPltfRequest{})
	// connected, not initialized: still ST_OP_NOT_INITIALIZED (E-SRV-001); the boards answer (0x01 not
	// initialized, motors 0x10 brake engaged: E-HW-005, E-HW-006)
	s = c.status()
	if s.OperationState != pc.StOpNotInitialized || s.IOStatus != 0x01 || s.MotorRightStatus != 0x11 {
		t.Fatalf("connected: state %d io %#x motor %#x", s.OperationState, s.IOStatus, s.MotorRightStatus)
	}
	c.send(&pc.InitPltfRequest{})
	s = c.status()
	if s.OperationState != pc.StOpReady || s.Initialized != pc.On || s.MotorRightStatus != 0 || s.IOBatteryVoltage != 25000 {
		t.Fatalf("initialized: state %d initialized %d motor %#x battery %d", s.OperationState, s.Initialized,
			s.MotorRightStatus, s.IOBatteryVoltage)
	}
	// the other port, with its own client, sees the same platform
	if other := h.dial(h.ports[0]).status(); other.OperationState != pc.StOpReady {
		t.Fatalf("the second port reports state %d", other.OperationState)
	}
}

package model

// The data, board and special-function commands (guide 6.3) and the GET_* replies other than the status.
//
// Rules (E-SRV-006): every GET_* is answered in every state; document, parameter and frame commands are allowed
// in every state; CAN-board and head-drive commands need the CAN bus up (after CMD_CONNECT_TO_PLTF); speech,
// sound and camera commands are allowed in any state and only logged (the emulator has none of that hardware).

import (
	"math"
	"strconv"

	pc "platformctrl"

	"pltf/emulator/internal/ids"
)

// boards: what the emulator keeps of its CAN boards. There are no boards on its bus: nothing is ever received,
// so CMD_GET_CAN_MESSAGES returns an empty list; outputs and sensors are reflected in GET_STATUS.
type boards struct {
	digout uint32 // IO board outputs (bit n = channel n, E-CMD-004)
	relays uint32 // relay board outputs 0..7 (E-HW-010)
	brake  [3]bool
	usMask int32 // active ultrasonic sensors (E-CMD-005)
	usOn   bool
	head   int32 // head drive position [deg]
	listen map[int32]bool
}

// busDown: CMD_SHUTDOWN_PLTF stops the ultrasonic measurement (the boards are silent, E-HW-004).
func (b *boards) busDown() { b.usOn = false }

// onBus wraps a command that needs the CAN bus up (E-SRV-006).
func onBus(do func(p *Platform, t pc.Telegram)) handler {
	return func(p *Platform, t pc.Telegram) Result {
		if !p.State.BusUp() {
			return p.refuse(t, "the CAN bus is not connected (E-SRV-006)")
		}
		do(p, t)
		return Result{}
	}
}

func logged(what string) handler {
	return func(p *Platform, t pc.Telegram) Result {
		p.Logf("%s: %s", t.TelegramName(), what)
		return Result{}
	}
}

func exit(p *Platform, t pc.Telegram) Result {
	halt(p)
	p.board.busDown()
	p.State = NotConnected
	p.Logf("exit: the platform shuts down (E-SRV-015)")
	return Result{Exit: true}
}

func setDigout(p *Platform, t pc.Telegram) Result {
	r := t.(*pc.SetDigoutRequest)
	if !p.State.BusUp() {
		return p.refuse(t, "the CAN bus is not connected (E-SRV-006)")
	}
	bits := &p.board.digout
	if r.Board == pc.TypeRelayboard {
		if r.Channel > 7 {
			return p.refuse(t, "the relay board has relays 0..7 (E-HW-010)")
		}
		bits = &p.board.relays
	}
	if r.Value == pc.OutputHigh {
		*bits |= 1 << uint(r.Channel)
	} else {
		*bits &^= 1 << uint(r.Channel)
	}
	p.Logf("digital output %d/%d = %d", r.Board, r.Channel, r.Value)
	return Result{}
}

func setFrame(p *Platform, t pc.Telegram) Result {
	r := t.(*pc.SetFrmPltfRequest)
	// E-HW-023: the estimate is replaced; the ideal emulator's body is its estimate. A running move goes on
	// to its remaining waypoints from the new frame.
	rest := p.Drive.Waypoints()
	p.Drive.Pose = frame(r.X, r.Y, r.Angle)
	if len(rest) > 0 {
		vt, wt := p.ipo()
		p.Drive.MoveThrough(rest, vt, wt)
	}
	p.Logf("platform frame set to %d, %d, %d", r.X, r.Y, r.Angle)
	return Result{}
}

func setParam(p *Platform, t pc.Telegram) Result {
	r := t.(*pc.SetPltfParamRequest)
	if err := p.Params.Set(r.Key, r.Value); err != nil {
		return p.refuse(t, strconv.Quote(r.Key)+": "+err.Error()) // E-PAR-007: no reply, the old value stays
	}
	p.Logf("parameter %q = %q", r.Key, r.Value)
	return Result{}
}

func getParam(p *Platform, t pc.Telegram) Result {
	key := t.(*pc.GetPltfParamRequest).Key
	par, ok := p.Params.Lookup(key)
	if !ok { // E-SRV-010: an unknown key is answered (key, "", 0, 0, 0, 0)
		return Result{Reply: &pc.GetPltfParamReply{Key: key}}
	}
	e := p.entry(par.Name)
	return Result{Reply: &pc.GetPltfParamReply{Key: e.Key, Value: e.Value, Category: e.Category,
		DataType: e.DataType, Minimum: e.Minimum, Maximum: e.Maximum}}
}

func (p *Platform) entry(key string) pc.ParamEntry {
	par, _ := p.Params.Lookup(key)
	lo, hi := par.WireBounds()
	return pc.ParamEntry{Key: par.Name, Value: p.Params.Text(par), Category: pc.ParamCategory(par.Category),
		DataType: pc.ParamDataType(par.Type), Minimum: lo, Maximum: hi}
}

func getParamVec(p *Platform, t pc.Telegram) Result {
	all := p.Params.All()
	out := make([]pc.ParamEntry, len(all))
	for i, par := range all {
		out[i] = p.entry(par.Name)
	}
	return Result{Reply: &pc.GetPltfParamVecReply{Parameters: out}}
}

// doc wraps a document command's outcome in the log.
func doc(do func(p *Platform, t pc.Telegram) error) handler {
	return func(p *Platform, t pc.Telegram) Result {
		if err := do(p, t); err != nil {
			return p.refuse(t, err.Error())
		}
		p.Logf("%s done", t.TelegramName())
		return Result{}
	}
}

func init() {
	more := map[uint8]handler{
		ids.SetBrake: onBus(func(p *Platform, t pc.Telegram) { // CMD_SET_BRAKE: 0 engages, 1 releases (E-CMD-015)
			r := t.(*pc.SetBrakeRequest)
			p.board.brake[r.Motor] = r.State == pc.BrakeEnabled
			p.Logf("brake of motor %d: %d", r.Motor, r.State)
		}),
		ids.SetDigout: setDigout,
		ids.StartUltrasonic: onBus(func(p *Platform, t pc.Telegram) {
			p.board.usMask, p.board.usOn = t.(*pc.StartUltrasonicRequest).ActiveChannels, true
			p.Logf("ultrasonic measurement started")
		}),
		ids.StopUltrasonic: onBus(func(p *Platform, t pc.Telegram) {
			p.board.usOn = false
			p.Logf("ultrasonic measurement stopped")
		}),
		ids.AddCanListeningId: onBus(func(p *Platform, t pc.Telegram) {
			p.board.listen[t.(*pc.AddCanListeningIdRequest).CanID] = true
		}),
		ids.RemoveCanListeningId: onBus(func(p *Platform, t pc.Telegram) {
			delete(p.board.listen, t.(*pc.RemoveCanListeningIdRequest).CanID)
		}),
		ids.SendCanMessage: onBus(func(p *Platform, t pc.Telegram) {
			p.Logf("CAN message %d sent (no boards on the emulator's bus)", t.(*pc.SendCanMessageRequest).CanID)
		}),
		ids.GetCanMessages: func(p *Platform, t pc.Telegram) Result {
			return Result{Reply: &pc.GetCanMessagesReply{Messages: []pc.CanMessage{}}}
		},
		ids.SetMap: doc(func(p *Platform, t pc.Telegram) error {
			r := t.(*pc.SetMapRequest)
			return p.Docs.Set(MapDoc, r.Name, r.XML)
		}),
		ids.GetMap: func(p *Platform, t pc.Telegram) Result {
			d := p.Docs.Active[MapDoc]
			return Result{Reply: &pc.GetMapReply{XML: d.XML, Name: d.Name}}
		},
		ids.LoadMap:      doc(func(p *Platform, t pc.Telegram) error { return p.Docs.Load(MapDoc) }),
		ids.SaveMap:      doc(func(p *Platform, t pc.Telegram) error { return p.Docs.Save(MapDoc) }),
		ids.MappingStart: func(p *Platform, t pc.Telegram) Result { p.mapping = true; p.Logf("mapping started"); return Result{} },
		ids.MappingReset: logged("mapping reset (the emulator builds no map)"),
		ids.MappingStop:  func(p *Platform, t pc.Telegram) Result { p.mapping = false; p.Logf("mapping stopped"); return Result{} },
		ids.SetRoadmap: doc(func(p *Platform, t pc.Telegram) error {
			r := t.(*pc.SetRoadmapRequest)
			return p.Docs.Set(RoadmapDoc, r.Name, r.XML)
		}),
		ids.GetRoadmap: func(p *Platform, t pc.Telegram) Result {
			d := p.Docs.Active[RoadmapDoc]
			return Result{Reply: &pc.GetRoadmapReply{XML: d.XML, Name: d.Name}}
		},
		ids.LoadRoadmap:     doc(func(p *Platform, t pc.Telegram) error { return p.Docs.Load(RoadmapDoc) }),
		ids.SaveRoadmap:     doc(func(p *Platform, t pc.Telegram) error { return p.Docs.Save(RoadmapDoc) }),
		ids.SetFrmPltf:      setFrame,
		ids.SetPltfParam:    setParam,
		ids.GetPltfParam:    getParam,
		ids.GetPltfParamVec: getParamVec,
		ids.SetProgram: doc(func(p *Platform, t pc.Telegram) error {
			return p.Docs.Set(ProgramDoc, "", t.(*pc.SetProgramRequest).XML)
		}),
		ids.GetProgram: func(p *Platform, t pc.Telegram) Result {
			return Result{Reply: &pc.GetProgramReply{XML: p.Docs.Active[ProgramDoc].XML}}
		},
		ids.LoadProgram: doc(func(p *Platform, t pc.Telegram) error { return p.Docs.Load(ProgramDoc) }),
		ids.SaveProgram: doc(func(p *Platform, t pc.Telegram) error { return p.Docs.Save(ProgramDoc) }),
		ids.SpeakText:   logged("no text-to-speech on the emulator"),
		ids.PlaySound:   logged("no loudspeaker on the emulator"),
		ids.GrabImage:   logged("no camera on the emulator"),
		ids.SetPosHeadDrive: onBus(func(p *Platform, t pc.Telegram) { // the head drive is at its position at once (ideal)
			p.board.head = t.(*pc.SetPosHeadDriveRequest).Angle
			p.Logf("head drive at %d deg", p.board.head)
		}),
		ids.SetVelHeadDrive:        onBus(func(p *Platform, t pc.Telegram) { p.Logf("head drive velocity (positions are reached at once)") }),
		ids.SetPosPanTiltCamera:    logged("no pan-tilt camera on the emulator"),
		ids.GetDebugData:           getDebugData,
		ids.MouseMove:              logged("mouse obstacle (the emulator has no obstacles)"),
		ids.SetLogEnabled:          logged("not used at the moment (E-CMD-010)"),
		ids.SetPostProcessFilename: logged("not used at the moment (E-CMD-011)"),
		ids.SetEvent:               logged("event (the emulator records and replays nothing)"),
		ids.GetCamera:              func(p *Platform, t pc.Telegram) Result { return Result{Reply: &pc.GetCameraReply{}} }, // E-REP-020
		ids.ShutdownHost:           logged("the host is never shut down (E-SRV-013)"),
	}
	for id, h := range more {
		handlers[id] = h
	}
}

// mrad converts rad/s to the status' 1/1000 rad/s (E-REP-005).
func mrad(w float64) int32 { return int32(math.Round(w * 1000)) }

package model

// The operation state chart (guide 4.2 figure 2; 6.3 CMD_START ... CMD_SET_MODE; errata E-SRV-001..004, E-SRV-018).
//
// Rule 1: everything that decides whether a chart command is allowed lives in this table. A pair that is absent
// is refused: logged, no reply (E-CMD-013), nothing changes.

import (
	pc "platformctrl"

	"pltf/emulator/internal/ids"
)

// State is a state of the chart. NotConnected and Connected are both reported as ST_OP_NOT_INITIALIZED with
// initialized = 0 (E-SRV-001).
type State int

// The states.
const (
	NotConnected State = iota
	Connected
	Ready
	Running
	Breaked
)

var stateNames = [...]string{"not connected", "connected", "ready", "running", "breaked"}

func (s State) String() string { return stateNames[s] }

// Reported is the operation state of GET_STATUS (E-SRV-001, E-CMD-003).
func (s State) Reported() pc.OperationState {
	return [...]pc.OperationState{pc.StOpNotInitialized, pc.StOpNotInitialized, pc.StOpReady, pc.StOpRunning,
		pc.StOpBreaked}[s]
}

// Initialized is the status' initialized flag.
func (s State) Initialized() bool { return s >= Ready }

// BusUp is true while the CAN bus is connected (every state after CMD_CONNECT_TO_PLTF until CMD_SHUTDOWN_PLTF).
func (s State) BusUp() bool { return s != NotConnected }

type edge struct {
	from State
	cmd  uint8
}

// transitions: where an allowed chart command leads.
var transitions = map[edge]State{
	// guide 4.2: "The initialization process starts with the command CMD_CONNECT_CAN" (E-CMD-002); E-SRV-002: once.
	{NotConnected, ids.ConnectToPltf}: Connected,
	// guide 4.2: "The command CMD_INIT_CAN initializes all hardware components"; E-SRV-002: only when connected.
	{Connected, ids.InitPltf}: Ready,
	// guide 6.3 CMD_SHUTDOWN_PLTF "Used to shutdown the CAN communication"; E-SRV-003: from every state with the bus up.
	{Connected, ids.ShutdownPltf}: NotConnected,
	{Ready, ids.ShutdownPltf}:     NotConnected,
	{Running, ids.ShutdownPltf}:   NotConnected,
	{Breaked, ids.ShutdownPltf}:   NotConnected,
	// guide 6.3 CMD_START: 'The operation state changes into the state "Moving"'; E-SRV-018: from Ready only.
	{Ready, ids.Start}: Running,
	// guide 6.3 CMD_BREAK: 'changes into the state "Break"'; E-SRV-018: from Running only.
	{Running, ids.Break}: Breaked,
	// guide 6.3 CMD_CONTINUE: 'changes into the state "Moving"'; E-SRV-018: from Breaked only.
	{Breaked, ids.Continue}: Running,
	// guide 6.3 CMD_STOP: 'changes into the state "Ready"'; E-SRV-004: refused in Ready.
	{Running, ids.Stop}: Ready,
	{Breaked, ids.Stop}: Ready,
	// guide 6.3 CMD_SET_MODE: 'The operation state has to be in "Ready" before changing to another motion mode'.
	{Ready, ids.SetMode}: Ready,
}

// Next is where cmd leads from s, and whether it is allowed there.
func Next(s State, cmd uint8) (State, bool) {
	to, ok := transitions[edge{s, cmd}]
	return to, ok
}

// moveModes: the move commands each motion mode takes in Running (guide 4.3; E-SRV-005, E-CMD-014). Every other
// mode (NO, JOYHARD, PROGRAM, POST_PROCESS_REPLAY) ignores all moves.
var moveModes = map[pc.MotionMode]map[uint8]bool{
	pc.ModeMotionVel:       {ids.MoveVelWheel: true, ids.MoveVel: true},
	pc.ModeMotionJoysoft:   {ids.MoveVel: true},
	pc.ModeMotionAutomatic: {ids.MovePath: true, ids.MoveToStation: true, ids.MoveAbs: true, ids.MoveRel: true},
}

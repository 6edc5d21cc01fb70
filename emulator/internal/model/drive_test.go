package model

import (
	"math"
	"testing"
)

func poseNear(t *testing.T, got, want Pose, how string) {
	t.Helper()
	if math.Abs(got.X-want.X) > 1e-6 || math.Abs(got.Y-want.Y) > 1e-6 || math.Abs(Normalize(got.Th-want.Th)) > 1e-9 {
		t.Fatalf("%s: %+v, want %+v", how, got, want)
	}
}

func TestArcIsExactInAnySteps(t *testing.T) {
	// 100 mm/s on a 200 mm circle: after a quarter circle (pi s) the platform is at (200, 200, pi/2)
	one, many := NewDrive(Pose{}), NewDrive(Pose{})
	one.SetVelocity(100, 0.5, math.Inf(1))
	many.SetVelocity(100, 0.5, math.Inf(1))
	one.Advance(math.Pi, math.Pi)
	for i := 1; i <= 1000; i++ {
		many.Advance(math.Pi*float64(i)/1000, math.Pi/1000)
	}
	poseNear(t, one.Pose, Pose{200, 200, math.Pi / 2}, "one step")
	poseNear(t, many.Pose, one.Pose, "1000 steps")
}

func TestVelocityDeadlineStopsAtItsTime(t *testing.T) {
	d := NewDrive(Pose{X: 10})
	d.SetVelocity(300, 0, 0.5)
	d.Advance(3, 3)
	poseNear(t, d.Pose, Pose{X: 160}, "0.5 s at 300 mm/s")
	if v, w := d.Velocity(); v != 0 || w != 0 || !math.IsInf(d.VelDeadline, 1) {
		t.Fatalf("still %v %v", v, w)
	}
}

func TestMoveThroughLegs(t *testing.T) {
	d := NewDrive(Pose{})
	d.MoveThrough([]Pose{{X: 0, Y: 1000, Th: math.Pi}}, 500, 1)
	// turn pi/2 (1.5708 s), drive 1000 mm (2 s), turn pi/2 (1.5708 s)
	if len(d.legs) != 3 {
		t.Fatalf("%d legs", len(d.legs))
	}
	d.Advance(1, 1)
	poseNear(t, d.Pose, Pose{Th: 1}, "turning")
	if v, w := d.Velocity(); v != 0 || w != 1 {
		t.Fatalf("velocity while turning %v %v", v, w)
	}
	if ended := d.Advance(math.Pi/2+1.5, math.Pi/2+0.5); ended {
		t.Fatal("ended early")
	}
	poseNear(t, d.Pose, Pose{Y: 750, Th: math.Pi / 2}, "on the line")
	if !d.Advance(100, 100-math.Pi/2-1.5) || d.Moving() {
		t.Fatal("the move did not end")
	}
	poseNear(t, d.Pose, Pose{Y: 1000, Th: math.Pi}, "at the target")
	// a target equal to the pose still ends (an empty leg)
	d.MoveThrough([]Pose{d.Pose}, 500, 1)
	if !d.Advance(100.001, 0.001) {
		t.Fatal("an empty move did not end")
	}
}

func TestHaltKeepsTheMove(t *testing.T) {
	d := NewDrive(Pose{})
	d.MoveThrough([]Pose{{X: 1000}}, 1000, 1)
	d.Advance(0.25, 0.25)
	d.Halted = true
	d.Advance(10, 9.75)
	poseNear(t, d.Pose, Pose{X: 250}, "halted")
	d.Halted = false
	d.Advance(10.5, 0.5)
	poseNear(t, d.Pose, Pose{X: 750}, "continued")
	if w := d.Waypoints(); len(w) != 1 || w[0].X != 1000 {
		t.Fatalf("waypoints %+v", w)
	}
}

func TestNormalizeAndCompose(t *testing.T) {
	for _, c := range [][2]float64{{math.Pi, math.Pi}, {-math.Pi, math.Pi}, {3 * math.Pi, math.Pi}, {-0.5, -0.5}, {7, 7 - 2*math.Pi}} {
		if got := Normalize(c[0]); math.Abs(got-c[1]) > 1e-12 {
			t.Errorf("Normalize(%v) = %v, want %v", c[0], got, c[1])
		}
	}
	poseNear(t, Compose(Pose{100, 0, math.Pi / 2}, Pose{1000, 0, math.Pi / 2}), Pose{100, 1000, math.Pi}, "compose")
}

package model

import (
	"math"
	"testing"
)

func TestRouteIsShortestAndUndirected(t *testing.T) {
	g, err := parseRoadmap([]byte(`<roadmap><stations>
	  <station id="a" name="A"><point x="0" y="0"/></station>
	  <station id="b"><point x="1000" y="0"/></station>
	  <station id="c" name="C" angle="-90"><point x="1000" y="1000"/></station>
	</stations><edges>
	  <edge startstation="b" endstation="a"/>
	  <edge startstation="c" endstation="b"><points><point x="1200" y="500"/></points></edge>
	  <edge startstation="a" endstation="c"><point x="0" y="3000"/><point x="1000" y="3000"/></edge>
	</edges></roadmap>`))
	if err != nil {
		t.Fatal(err)
	}
	route, ok := g.route(Pose{X: 10, Y: -10}, g.name["C"])
	want := []Pose{{0, 0, 0}, {1000, 0, 0}, {1200, 500, 0}, {1000, 1000, -math.Pi / 2}}
	if !ok || len(route) != len(want) {
		t.Fatalf("route %+v", route)
	}
	for i := range want {
		if route[i] != want[i] {
			t.Fatalf("waypoint %d: %+v, want %+v", i, route[i], want[i])
		}
	}
	// from near C back to A: the same edges the other way, the inner point reversed
	back, _ := g.route(Pose{X: 990, Y: 990}, g.index["a"])
	if len(back) != 4 || back[1] != (Pose{1200, 500, 0}) || back[3].X != 0 {
		t.Fatalf("back %+v", back)
	}
}

func TestRoadmapErrors(t *testing.T) {
	for _, doc := range []string{
		`<roadmap><stations><station id="a"><point x="one" y="0"/></station></stations><edges/></roadmap>`,
		`<roadmap><stations><station id="a"><point x="0" y="0"/></station></stations>` +
			`<edges><edge startstation="a" endstation="z"/></edges></roadmap>`,
	} {
		if _, err := parseRoadmap([]byte(doc)); err == nil {
			t.Errorf("%q read", doc)
		}
	}
	g, _ := parseRoadmap([]byte(`<roadmap><stations><station id="a"><point x="0" y="0"/></station>` +
		`<station id="b"><point x="9" y="9"/></station></stations><edges/></roadmap>`))
	if _, ok := g.route(Pose{}, g.index["b"]); ok {
		t.Fatal("a route between unconnected stations")
	}
}

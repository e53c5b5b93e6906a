// Decodes an LCM event log written by the C++ side with lcm-spy's own type lookup
// (lcm.spy.LCMTypeDatabase scans the class path, as lcm-spy does): it picks the class by
// the fingerprint at the start of each message, decodes, re-encodes and requires the same
// bytes (no field lost or changed), and checks a few values against the C++ fixtures'
// formulas (tests/lcm/message_fixtures.hpp: tick t of a block carries values computed from t;
// the fixtures' blocks have one axis, so every array holds n_values = n_ticks elements). It also requires the jar to hold exactly the nine
// hystloop types.
//
//   java -cp hystloop_lcmtypes.jar:lcm.jar:. DecodeCheck <jar> <log> <rounds>
import java.io.EOFException;
import java.nio.ByteBuffer;
import java.util.Arrays;
import java.util.Enumeration;
import java.util.HashMap;
import java.util.Map;
import java.util.TreeMap;
import java.util.jar.JarEntry;
import java.util.jar.JarFile;

import lcm.lcm.LCMDataOutputStream;
import lcm.lcm.LCMEncodable;
import lcm.logging.Log;

public class DecodeCheck {
  static int failures = 0;

  static void fail(String what) {
    System.out.println("FAIL: " + what);
    failures++;
  }

  public static void main(String[] args) throws Exception {
    if (args.length != 3) {
      System.err.println("usage: DecodeCheck <types jar> <log> <rounds>");
      System.exit(2);
    }
    long rounds = Long.parseLong(args[2]);
    long rare = (rounds + 9) / 10;

    Map<Long, Class<?>> byFingerprint = new HashMap<>();
    try (JarFile jar = new JarFile(args[0])) {
      for (Enumeration<JarEntry> e = jar.entries(); e.hasMoreElements();) {
        String name = e.nextElement().getName();
        if (!name.endsWith(".class") || name.contains("$")) continue;
        Class<?> c = Class.forName(name.substring(0, name.length() - 6).replace('/', '.'));
        if (LCMEncodable.class.isAssignableFrom(c)) {
          byFingerprint.put(c.getField("LCM_FINGERPRINT").getLong(null), c);
        }
      }
    }
    if (byFingerprint.size() != 9) fail("expected 9 LCM types in the jar, found " + byFingerprint.size());

    lcm.spy.LCMTypeDatabase spyTypes = new lcm.spy.LCMTypeDatabase();
    for (Map.Entry<Long, Class<?>> e : byFingerprint.entrySet()) {
      if (spyTypes.getClassByFingerprint(e.getKey()) != e.getValue()) {
        fail("lcm-spy's type database does not find " + e.getValue().getName());
      }
    }

    Map<String, Long> counts = new TreeMap<>();
    Log log = new Log(args[1], "r");
    while (true) {
      Log.Event ev;
      try {
        ev = log.readNext();
      } catch (EOFException end) {
        break;
      }
      long fingerprint = ByteBuffer.wrap(ev.data, 0, 8).getLong();
      Class<?> type = spyTypes.getClassByFingerprint(fingerprint);
      if (type == null) {
        fail(ev.channel + ": no type in the jar has fingerprint " + fingerprint);
        continue;
      }
      Object msg = type.getConstructor(byte[].class).newInstance((Object) ev.data);
      LCMDataOutputStream out = new LCMDataOutputStream();
      ((LCMEncodable) msg).encode(out);
      if (!Arrays.equals(out.toByteArray(), ev.data)) fail(ev.channel + ": re-encoding differs");
      counts.merge(ev.channel + " " + type.getSimpleName(), 1L, Long::sum);

      if (msg instanceof hystloop.sensor_block_t) {
        hystloop.sensor_block_t s = (hystloop.sensor_block_t) msg;
        int n = s.n_ticks;
        if (n < 1 || s.n_axes != 1 || s.n_values != n || s.u_V.length != n || s.u_ff_V.length != n
            || s.u_fb_V.length != n || s.y_ref_m.length != n || s.y_m.length != n || s.flags.length != n) {
          fail("sensor block at seq " + s.seq + ": not one axis, or its arrays do not hold n_ticks = " + n);
        } else {
          for (int i = 0; i < n; ++i) {
            long t = s.seq + i;
            if (s.u_V[i] != 12.5 + 1.0e-3 * t || s.y_m[i] != -1.6e-6 + 1.0e-12 * t) fail("sensor values at tick " + t);
            if ((t % 5 == 4) != Double.isNaN(s.y_ref_m[i])) fail("sensor reference (NaN = none) at tick " + t);
          }
        }
      } else if (msg instanceof hystloop.command_block_t) {
        hystloop.command_block_t c = (hystloop.command_block_t) msg;
        int n = c.n_ticks;
        if (n < 1 || c.n_axes != 1 || c.n_values != n || c.u_ff_V.length != n || c.y_ref_m.length != n
            || c.params_version.length != n || c.mode.length != n) {
          fail("command block at seq " + c.seq + ": not one axis, or its arrays do not hold n_ticks = " + n);
        } else {
          for (int i = 0; i < n; ++i) {
            long t = c.seq + i;
            if (c.u_ff_V[i] != 30.0 + 1.0e-3 * t || c.params_version[i] != 3 + t % 5) fail("command values at tick " + t);
          }
        }
      } else if (msg instanceof hystloop.trajectory_t) {
        hystloop.trajectory_t t = (hystloop.trajectory_t) msg;
        if (t.n_points != 1 + (t.version - 1) % 6 || t.points_y_m.length != t.n_points) fail("trajectory points");
      } else if (msg instanceof hystloop.model_params_t) {
        hystloop.model_params_t m = (hystloop.model_params_t) msg;
        if (m.kind != (m.version - 1) % 4) fail("model params kind " + m.kind + " at version " + m.version);
        if (m.kind == hystloop.model_params_t.KIND_PI
            && (m.pi_weights.length != m.n_operators || m.pi_thresholds_V.length != m.n_operators)) {
          fail("PI arrays do not hold n_operators = " + m.n_operators);
        }
      } else if (msg instanceof hystloop.mem_params_t) {
        hystloop.mem_params_t p = (hystloop.mem_params_t) msg;
        if (!p.source.equals("reident@lab-host-" + (p.version - 1))) fail("params source '" + p.source + "'");
      }
    }
    log.close();

    Map<String, Long> expected = new TreeMap<>();
    expected.put("HX_SENSOR sensor_block_t", rounds);
    expected.put("HX_COMMAND command_block_t", rounds);
    expected.put("HX_TRAJECTORY trajectory_t", rare);
    expected.put("HX_PARAMS mem_params_t", rare);
    expected.put("HX_MODEL model_params_t", rare);
    expected.put("HX_STATUS service_status_t", rare);
    expected.put("HX_CONTROL control_t", rare);
    if (!counts.equals(expected)) fail("decoded " + counts + ", expected " + expected);
    System.out.println("decoded " + counts);
    System.exit(failures == 0 ? 0 : 1);
  }
}

// Decodes every event of an LCM log with the Java classes of the cairn types jar, finding each
// event's class by its fingerprint, as lcm-spy does. Exit 0 when every event decoded.
import java.io.EOFException;
import java.lang.reflect.Field;
import java.nio.ByteBuffer;
import java.util.Enumeration;
import java.util.HashMap;
import java.util.Map;
import java.util.jar.JarEntry;
import java.util.jar.JarFile;
import lcm.logging.Log;

public class DecodeLog {
  public static void main(String[] args) throws Exception {
    Map<Long, Class<?>> byFingerprint = new HashMap<>();
    try (JarFile jar = new JarFile(args[0])) {
      for (Enumeration<JarEntry> e = jar.entries(); e.hasMoreElements();) {
        String name = e.nextElement().getName();
        if (!name.endsWith(".class") || name.contains("$")) continue;
        Class<?> c = Class.forName(name.replace('/', '.').replace(".class", ""));
        Field f = c.getField("LCM_FINGERPRINT");
        byFingerprint.put(f.getLong(null), c);
      }
    }
    Log log = new Log(args[1], "r");
    int ok = 0, failed = 0;
    while (true) {
      Log.Event ev;
      try {
        ev = log.readNext();
      } catch (EOFException eof) {
        break;
      }
      long fingerprint = ByteBuffer.wrap(ev.data, 0, 8).getLong();
      Class<?> c = byFingerprint.get(fingerprint);
      if (c == null) {
        System.out.println("UNKNOWN fingerprint on " + ev.channel);
        failed++;
        continue;
      }
      try {
        c.getConstructor(byte[].class).newInstance((Object) ev.data);
        ok++;
      } catch (Exception ex) {
        System.out.println("FAILED " + ev.channel + ": " + ex.getCause());
        failed++;
      }
    }
    System.out.println("decoded " + ok + " failed " + failed + " classes " + byFingerprint.size());
    System.exit(failed == 0 && ok > 0 ? 0 : 1);
  }
}
